"""People: users with argon2-hashed passwords, login sessions, API tokens and one-time login
links, all in the store; and the login rate limit.

Secrets (session ids, tokens, links) are random and long, so the store keeps only their
SHA-256: a stolen database file lets nobody in. Passwords are argon2 hashes.
"""

from __future__ import annotations

import hashlib
import re
import secrets
import threading
import time
from collections import deque
from dataclasses import dataclass

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError

from api.auth import Role
from backend.errors import ApiError, Conflict, Invalid, NotFound
from backend.services.auth import Actor
from backend.services.store import Row, Store

# what a login of an unknown name (or of a user without a password) is checked against, so it
# costs as much as a known name's: the hash of a random secret thrown away, with
# PasswordHasher's parameters (a test keeps them equal). A constant, not hashed at start: an
# argon2 hash costs a tenth of a second at every service start and command-line call.
UNKNOWN_USER_HASH = (
    "$argon2id$v=19$m=65536,t=3,p=4$LUsLXHDYj+EjqK6DGSh+tA"
    "$59wDQPeZHLUrggxBimGj3sAVluQXePgBKkajFZuuxwg"
)
SESSION_S = 12 * 3600.0  # a shift; then log in again
TICKET_S = 300.0  # a ticket for one URL (a viewer that cannot send the session) lives this long
WS_TICKET_S = 30.0  # a websocket's ticket: fetched just before the connect
# what a websocket ticket opens: a machine's telemetry, a class's console grid (the route
# itself still checks the role)
WEBSOCKET_PATH = re.compile(r"/api/machines/[^/]+/telemetry|/api/classes/[^/]+/grid")
LAST_USED_S = 60.0  # a token's last use is written at most this often (not once per request)
ONCE_S = 3600.0  # a one-time login link is good for an hour
LOGIN_FAILURES = 5  # failed logins per address within LOGIN_WINDOW_S before 429
LOGIN_WINDOW_S = 60.0
FIRST_ADMIN = "admin"  # created without a password on a store with no users

_SCHEMA = """
CREATE TABLE IF NOT EXISTS users (
    name TEXT PRIMARY KEY,
    role TEXT NOT NULL,
    hash TEXT NOT NULL,            -- argon2; '' = no password (one-time links only)
    created REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS sessions (
    digest TEXT PRIMARY KEY,       -- SHA-256 of the session id
    user TEXT NOT NULL,
    csrf TEXT NOT NULL,
    created REAL NOT NULL,
    expires REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS tokens (
    digest TEXT PRIMARY KEY,       -- SHA-256 of the token
    user TEXT NOT NULL,
    kind TEXT NOT NULL,            -- 'api' (scripts) or 'once' (a login link)
    label TEXT NOT NULL,
    created REAL NOT NULL,
    expires REAL,                  -- NULL: until revoked
    last_used REAL                 -- to within LAST_USED_S; NULL: never
);
"""
_DIGEST_CHARS = 16  # of a public id


def digest(secret: str) -> str:
    """What the store keeps of a session id or token (SHA-256, hex)."""
    return hashlib.sha256(secret.encode()).hexdigest()


def public_id(kind: str, secret: str) -> str:
    """A session's or token's id that others may see (who holds control): a prefix of the
    digest the store keeps, which gives nothing away."""
    return f"{kind}-{digest(secret)[:_DIGEST_CHARS]}"


def _digest_prefix(public: str, kind: str) -> str | None:
    """The digest prefix a public id of this kind names (None: not such an id)."""
    head, _, prefix = public.partition("-")
    ok = head == kind and re.fullmatch(f"[0-9a-f]{{{_DIGEST_CHARS}}}", prefix)
    return prefix if ok else None


@dataclass(frozen=True)
class User:
    name: str
    role: Role


@dataclass(frozen=True)
class Session:
    """A live login session: who, and the CSRF token its page must echo."""

    user: User
    csrf: str


@dataclass(frozen=True)
class UserEntry:
    name: str
    role: Role
    created: float


@dataclass(frozen=True)
class TokenEntry:
    """An API token as others may see it: its public id, never the token."""

    id: str
    user: str
    label: str
    created: float
    last_used: float | None


@dataclass(frozen=True)
class Ticket:
    """Lets one request of `scope_type` ('http' GETs or 'websocket') on a path matching `path`
    act as `actor` until `until` (monotonic)."""

    actor: Actor
    scope_type: str
    path: re.Pattern[str]
    until: float


class AccountError(ApiError):
    """A user management request that cannot be carried out."""


class NoSuchAccount(AccountError, NotFound):
    """An unknown user or API token."""


class AccountConflict(AccountError, Conflict):
    """A name that is taken, or the last admin to remove or demote."""


class BadPassword(AccountError, Invalid):
    """A password too short, or typed differently twice (the command line)."""


class Accounts:
    """Users, sessions and tokens of one store."""

    def __init__(self, store: Store) -> None:
        self.store = store
        store.script(_SCHEMA)
        self._hasher = PasswordHasher()
        self._failures: dict[str, deque[float]] = {}
        self._tickets: dict[str, Ticket] = {}
        self._used: dict[str, float] = {}  # token digest -> monotonic time last_used was written
        self._lock = threading.Lock()
        columns = [r["name"] for r in store.query("PRAGMA table_info(tokens)")]
        if "last_used" not in columns:  # a store of an earlier version
            store.run("ALTER TABLE tokens ADD COLUMN last_used REAL")

    # --- users ------------------------------------------------------------------------------
    def users(self) -> list[UserEntry]:
        rows = self.store.query("SELECT name, role, created FROM users ORDER BY created")
        return [UserEntry(r["name"], Role(r["role"]), r["created"]) for r in rows]

    def add_user(self, name: str, role: Role, password: str | None) -> None:
        if self._user(name) is not None:
            raise AccountConflict(f"user {name!r} exists")
        hashed = self._hasher.hash(password) if password else ""
        self.store.run(
            "INSERT INTO users VALUES (?, ?, ?, ?)", (name, role.value, hashed, time.time())
        )

    def remove_user(self, name: str) -> None:
        """Remove a user with their sessions and tokens (never the last admin)."""
        self._keep_an_admin(name, "remove")
        for table in ("users WHERE name", "sessions WHERE user", "tokens WHERE user"):
            self.store.run(f"DELETE FROM {table} = ?", (name,))

    def set_role(self, name: str, role: Role) -> None:
        """A new role (never demoting the last admin); it applies from the next request."""
        if self._user(name) is None:
            raise NoSuchAccount(f"no user {name!r}")
        if role != Role.ADMIN:
            self._keep_an_admin(name, "demote")
        self.store.run("UPDATE users SET role = ? WHERE name = ?", (role.value, name))

    def _keep_an_admin(self, name: str, doing: str) -> None:
        """Refuse to take away the last admin: nobody could manage users any more."""
        user = self._user(name)
        if user is None:
            raise NoSuchAccount(f"no user {name!r}")
        sql = "SELECT COUNT(*) AS n FROM users WHERE role = ?"
        admins = self.store.query(sql, (Role.ADMIN.value,))[0]["n"]
        if user["role"] == Role.ADMIN.value and admins <= 1:
            raise AccountConflict(f"{name} is the last admin: cannot {doing} them")

    def set_password(self, name: str, password: str) -> None:
        """A new password; the user's sessions end."""
        if self._user(name) is None:
            raise NoSuchAccount(f"no user {name!r}")
        self.store.run(
            "UPDATE users SET hash = ? WHERE name = ?", (self._hasher.hash(password), name)
        )
        self.store.run("DELETE FROM sessions WHERE user = ?", (name,))

    def ensure_admin(self) -> bool:
        """On a store without users, create the first admin (no password); true if created."""
        if self.store.query("SELECT 1 FROM users LIMIT 1"):
            return False
        self.add_user(FIRST_ADMIN, Role.ADMIN, None)
        return True

    def first_admin(self) -> str | None:
        sql = "SELECT name FROM users WHERE role = ? ORDER BY created"
        rows = self.store.query(sql, (Role.ADMIN.value,))
        return rows[0]["name"] if rows else None

    def _user(self, name: str) -> Row | None:
        """The user's role and hash."""
        rows = self.store.query("SELECT role, hash FROM users WHERE name = ?", (name,))
        return rows[0] if rows else None

    # --- logging in -------------------------------------------------------------------------
    def check_password(self, name: str, password: str) -> User | None:
        """The user if the password is theirs (as slow for an unknown name as for a known)."""
        user = self._user(name)
        hashed = user["hash"] if user and user["hash"] else UNKNOWN_USER_HASH
        ok: bool
        try:
            ok = self._hasher.verify(hashed, password)
        except (VerificationError, InvalidHashError):
            ok = False
        return User(name, Role(user["role"])) if ok and user and user["hash"] else None

    def throttled(self, address: str) -> bool:
        """Too many failed logins from this address lately."""
        now = time.monotonic()
        with self._lock:
            recent = self._failures.get(address)
            while recent and now - recent[0] > LOGIN_WINDOW_S:
                recent.popleft()
            return recent is not None and len(recent) >= LOGIN_FAILURES

    def failed(self, address: str) -> None:
        with self._lock:
            self._failures.setdefault(address, deque()).append(time.monotonic())

    # --- sessions ---------------------------------------------------------------------------
    def new_session(self, name: str) -> tuple[str, str]:
        """(session id, CSRF token) of a new session of the user."""
        sid, csrf = secrets.token_urlsafe(32), secrets.token_urlsafe(24)
        now = time.time()
        self.store.run(
            "INSERT INTO sessions VALUES (?, ?, ?, ?, ?)",
            (digest(sid), name, csrf, now, now + SESSION_S),
        )
        return sid, csrf

    def session(self, sid: str) -> Session | None:
        rows = self.store.query(
            "SELECT s.user, u.role, s.csrf FROM sessions s JOIN users u ON u.name = s.user "
            "WHERE s.digest = ? AND s.expires > ?",
            (digest(sid), time.time()),
        )
        if not rows:
            return None
        r = rows[0]
        return Session(User(r["user"], Role(r["role"])), r["csrf"])

    def sessions_of(self, name: str) -> list[tuple[str, float]]:
        """(digest, expiry unix time) of each of the user's live sessions."""
        rows = self.store.query(
            "SELECT digest, expires FROM sessions WHERE user = ? AND expires > ?",
            (name, time.time()),
        )
        return [(r["digest"], float(r["expires"])) for r in rows]

    def end_session(self, sid: str) -> None:
        self.store.run("DELETE FROM sessions WHERE digest = ?", (digest(sid),))

    def end_logins_of(self, name: str) -> None:
        """End every session of the user and void its unused login links (its API tokens
        stay): a login whose link leaked is taken back."""
        self.store.run("DELETE FROM sessions WHERE user = ?", (name,))
        self.store.run("DELETE FROM tokens WHERE user = ? AND kind = 'once'", (name,))

    # --- tickets: one URL, once, soon ------------------------------------------------------
    def issue_ticket(self, actor: Actor, path: str) -> str:
        """A ticket that lets one GET of `path` act as `actor` within TICKET_S (for a client
        of ours that cannot send the session cookie: the Rerun viewer's loader)."""
        return self._issue(actor, "http", re.compile(re.escape(path)), TICKET_S)

    def issue_ws_ticket(self, actor: Actor, lifetime_s: float = WS_TICKET_S) -> str:
        """A ticket that opens one websocket (telemetry, a class's grid) as `actor` within
        `lifetime_s` (browsers cannot send headers on a websocket, and the cookie alone is
        refused)."""
        return self._issue(actor, "websocket", WEBSOCKET_PATH, lifetime_s)

    def _issue(
        self, actor: Actor, scope_type: str, path: re.Pattern[str], lifetime_s: float
    ) -> str:
        ticket = secrets.token_urlsafe(24)
        now = time.monotonic()
        with self._lock:
            for t in [t for t, found in self._tickets.items() if found.until < now]:
                del self._tickets[t]
            self._tickets[ticket] = Ticket(actor, scope_type, path, now + lifetime_s)
        return ticket

    def redeem_ticket(self, ticket: str, scope_type: str, path: str) -> Actor | None:
        """Who the ticket is for, if it is for this kind of request and path, still good, and
        its session still live; it is used up."""
        with self._lock:
            found = self._tickets.get(ticket)
            if found is None or found.scope_type != scope_type or not found.path.fullmatch(path):
                return None  # another path does not use it up
            del self._tickets[ticket]
        if found.until < time.monotonic() or found.actor.session not in self.live():
            return None
        return found.actor

    def live(self) -> dict[str, str]:
        """Public id -> user of every live session and API token (what a websocket or a
        control holder acts through: the rest have ended)."""
        now = time.time()
        n = _DIGEST_CHARS
        rows = self.store.query(
            f"SELECT 'session-' || substr(s.digest, 1, {n}) AS id, s.user FROM sessions s "
            "JOIN users u ON u.name = s.user WHERE s.expires > ? "
            f"UNION ALL SELECT 'token-' || substr(t.digest, 1, {n}), t.user FROM tokens t "
            "JOIN users u ON u.name = t.user WHERE t.kind = 'api'",
            (now,),
        )
        return {r["id"]: r["user"] for r in rows}

    # --- tokens and one-time links ----------------------------------------------------------
    def new_token(
        self, name: str, label: str = "", once: bool = False, lifetime_s: float = ONCE_S
    ) -> str:
        """An API token for scripts, or a one-time login link's token (good for
        `lifetime_s`, an hour unless told)."""
        if self._user(name) is None:
            raise NoSuchAccount(f"no user {name!r}")
        token = secrets.token_urlsafe(32)
        now = time.time()
        self.store.run(
            "INSERT INTO tokens VALUES (?, ?, ?, ?, ?, ?, NULL)",
            (
                digest(token),
                name,
                "once" if once else "api",
                label,
                now,
                now + lifetime_s if once else None,
            ),
        )
        return token

    def token_user(self, token: str) -> User | None:
        """Whose API token this is (its last use noted, at most once a LAST_USED_S)."""
        user = self._token("api", token)
        if user is not None:
            key, now = digest(token), time.monotonic()
            with self._lock:
                due = now - self._used.get(key, -LAST_USED_S) >= LAST_USED_S
                if due:
                    self._used[key] = now
            if due:
                sql = "UPDATE tokens SET last_used = ? WHERE digest = ?"
                self.store.run(sql, (time.time(), key))
        return user

    def tokens(self, user: str | None = None) -> list[TokenEntry]:
        """The API tokens of a user (everyone's without one), oldest first."""
        sql = "SELECT digest, user, label, created, last_used FROM tokens WHERE kind = 'api'"
        args: tuple[object, ...] = ()
        if user is not None:
            sql, args = sql + " AND user = ?", (user,)
        rows = self.store.query(sql + " ORDER BY created", args)
        return [
            TokenEntry(
                f"token-{r['digest'][:_DIGEST_CHARS]}",
                r["user"],
                r["label"],
                r["created"],
                r["last_used"],
            )
            for r in rows
        ]

    def token(self, token_id: str) -> TokenEntry:
        """An API token by its public id; NoSuchAccount when there is none."""
        prefix = _digest_prefix(token_id, "token")
        found = [t for t in self.tokens() if prefix and t.id == token_id]
        if not found:
            raise NoSuchAccount(f"no API token {token_id}")
        return found[0]

    def revoke_token(self, token_id: str) -> None:
        """Revoke an API token by its public id: refused from the next request on."""
        self.token(token_id)
        sql = "DELETE FROM tokens WHERE kind = 'api' AND substr(digest, 1, ?) = ?"
        self.store.run(sql, (_DIGEST_CHARS, _digest_prefix(token_id, "token")))

    def redeem_once(self, token: str) -> User | None:
        """Whose login link this is; the link is used up."""
        me = self._token("once", token)
        if me is not None:
            self.store.run("DELETE FROM tokens WHERE digest = ?", (digest(token),))
        return me

    def _token(self, kind: str, token: str) -> User | None:
        rows = self.store.query(
            "SELECT t.user, u.role FROM tokens t JOIN users u ON u.name = t.user "
            "WHERE t.digest = ? AND t.kind = ? AND (t.expires IS NULL OR t.expires > ?)",
            (digest(token), kind, time.time()),
        )
        return User(rows[0]["user"], Role(rows[0]["role"])) if rows else None
