"""Share links: an expiring, revocable, read-only view of one machine for someone without an
account (the expert a service technician calls in, a customer watching the acceptance).

A link is a secret in a URL (`/share/<token>`; the store keeps its digest only). Opening it
starts a session of the link's own guest login (`guest-<id>`, role observer), which sees
the link's machine only and may only watch (api/auth.py: a guest's actions are OBSERVE):
the live view, its history, its traces. The session ends when the link expires or is
revoked, which removes the guest login (its websockets close within seconds). Every opening
is audited.
"""

from __future__ import annotations

import secrets
import threading
import time
from dataclasses import dataclass

from api.auth import Role
from api.share import ShareLink
from backend.errors import not_found
from backend.services.accounts import Accounts, digest
from backend.services.store import Row, Store

SCHEMA = """
CREATE TABLE IF NOT EXISTS share_links (
    id TEXT PRIMARY KEY,
    digest TEXT NOT NULL UNIQUE,     -- of the secret in the link
    machine TEXT NOT NULL,
    label TEXT NOT NULL,
    created REAL NOT NULL,
    created_by TEXT NOT NULL,
    expires REAL NOT NULL,
    revoked REAL,                    -- when, by `revoked_by`; NULL while it holds
    revoked_by TEXT NOT NULL DEFAULT '',
    uses INTEGER NOT NULL DEFAULT 0
);
"""
PREFIX = "guest-"  # a guest login's name: PREFIX + the link's id
SWEEP_S = 5.0  # how often expired links' logins are removed


@dataclass(frozen=True)
class Guest:
    """What a guest login may see: one machine, until the link expires."""

    link: str
    machine: str
    expires: float
    label: str = ""


def _link(r: Row, watching: int = 0) -> ShareLink:
    now = time.time()
    return ShareLink(
        id=r["id"],
        machine=r["machine"],
        label=r["label"],
        created_unix=r["created"],
        created_by=r["created_by"],
        expires_unix=r["expires"],
        revoked_unix=r["revoked"],
        revoked_by=r["revoked_by"],
        uses=r["uses"],
        active=r["revoked"] is None and r["expires"] > now,
        guest=PREFIX + r["id"],
        watching=watching,
    )


class Shares:
    """The share links of every machine, and their guests."""

    def __init__(self, store: Store, accounts: Accounts) -> None:
        self.store, self.accounts = store, accounts
        store.script(SCHEMA)
        self._guests: dict[str, Guest] = {}  # guest login → what it may see
        self._lock = threading.Lock()
        for r in store.query("SELECT * FROM share_links WHERE revoked IS NULL"):
            self._guests[PREFIX + r["id"]] = Guest(r["id"], r["machine"], r["expires"], r["label"])
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="share-links", daemon=True)

    def start(self) -> None:
        self.sweep()
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def create(self, mid: str, hours: float, label: str, by: str) -> tuple[ShareLink, str]:
        """A new link to the machine, valid `hours`; the link and its secret (shown once)."""
        lid, token = secrets.token_hex(6), secrets.token_urlsafe(24)
        now = time.time()
        expires = now + hours * 3600.0
        self.accounts.add_user(PREFIX + lid, Role.OBSERVER, None)
        self.store.run(
            "INSERT INTO share_links (id, digest, machine, label, created, created_by, expires) "
            "VALUES (?, ?, ?, ?, ?, ?, ?)",
            (lid, digest(token), mid, label, now, by, expires),
        )
        with self._lock:
            self._guests[PREFIX + lid] = Guest(lid, mid, expires, label)
        return self.get(mid, lid), token

    def of(self, mid: str, watching: dict[str, int]) -> list[ShareLink]:
        """The machine's links, newest first, with how many of each one's guests watch."""
        rows = self.store.query(
            "SELECT * FROM share_links WHERE machine = ? ORDER BY created DESC", (mid,)
        )
        return [_link(r, watching.get(PREFIX + r["id"], 0)) for r in rows]

    def get(self, mid: str, lid: str) -> ShareLink:
        rows = self.store.query(
            "SELECT * FROM share_links WHERE machine = ? AND id = ?", (mid, lid)
        )
        if not rows:
            raise not_found(f"share link {lid} of machine {mid}")
        return _link(rows[0])

    def revoke(self, mid: str, lid: str, by: str) -> ShareLink:
        """End the link now: its guests' sessions end with its login."""
        link = self.get(mid, lid)
        if link.revoked_unix is None:
            self.store.run(
                "UPDATE share_links SET revoked = ?, revoked_by = ? WHERE id = ?",
                (time.time(), by, lid),
            )
            self._end(lid)
        return self.get(mid, lid)

    def redeem(self, token: str) -> tuple[ShareLink, str] | None:
        """The link a secret opens and its guest login, counted as used; None for an unknown,
        expired or revoked one."""
        rows = self.store.query(
            "SELECT * FROM share_links WHERE digest = ? AND revoked IS NULL AND expires > ?",
            (digest(token), time.time()),
        )
        if not rows:
            return None
        lid = rows[0]["id"]
        self.store.run("UPDATE share_links SET uses = uses + 1 WHERE id = ?", (lid,))
        return _link(rows[0]), PREFIX + lid

    def guest(self, user: str) -> Guest | None:
        """What a login may see when it is a share link's guest (None: it is no guest)."""
        if not user.startswith(PREFIX):
            return None
        with self._lock:
            return self._guests.get(user)

    def sweep(self) -> None:
        """Remove the logins of links that expired (their sessions end with them)."""
        now = time.time()
        with self._lock:
            gone = [g.link for g in self._guests.values() if g.expires <= now]
        for lid in gone:
            self._end(lid)

    def _end(self, lid: str) -> None:
        with self._lock:
            self._guests.pop(PREFIX + lid, None)
        if any(u.name == PREFIX + lid for u in self.accounts.users()):
            self.accounts.remove_user(PREFIX + lid)

    def _run(self) -> None:
        while not self._stop.wait(SWEEP_S):
            self.sweep()
