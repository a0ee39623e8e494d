"""Who may do what: roles, actions and the one authorization matrix. Roles, actions and the
rule of every route are part of the contract, so the UI can show what a user may do."""

from __future__ import annotations

from enum import StrEnum

from pydantic import BaseModel, Field


class Role(StrEnum):
    """Roles of a user of the HMI, each allowed what the one before it may, and more."""

    OBSERVER = "observer"  # watches; captures, saves and exports traces; reads programs
    OPERATOR = "operator"  # commands, jogs and writes parameters while holding control;
    # writes programs, runs assistants, signs commissioning reports off; a class's student
    # is an operator who sees only the machine of their seat
    INSTRUCTOR = "instructor"  # also takes control from others, paces the simulation and
    # runs classes (faults, snapshots, the console)
    ADMIN = "admin"  # everything, and users, machines and the service


class Action(StrEnum):
    """What a request does, as the authorization matrix sees it."""

    OBSERVE = "observe"  # status, telemetry, parameters, traces, programs, a machine's audit
    NOTE = "note"  # write in a machine's logbook (its history), acknowledge its job errors
    ASK = "ask"  # ask the holder of a machine for control, with a message (or withdraw it)
    TOKENS = "tokens"  # make and revoke one's own API tokens
    SHARE = "share"  # make and revoke a machine's read-only share links for guests
    CAPTURE = "capture"  # scope set-up, arm, force, stop; save, annotate, view traces
    RECORD = "record"  # long recordings to disk (within the recordings quota)
    DELETE_TRACE = "delete_trace"
    PROGRAMS = "programs"  # write and delete stored NC programs (service-wide, no control)
    CONTROL = "control"  # take a free machine, request, release, grant or refuse control
    STOP = "stop"  # emergency stop: any operator, holding control or not
    COMMAND = "command"  # NC commands, jog, reset, power cycle: only while holding control
    CONFIGURE = "configure"  # parameter writes and imports: only while holding control
    VERSIONS = "versions"  # take, delete parameter versions of a machine, set its baseline
    ASSIST = "assist"  # commissioning assistants on a copy of a machine (a process for seconds)
    SIGN_OFF = "sign_off"  # sign a machine's commissioning report off
    EXERCISE = "exercise"  # read the exercise of one's seat, take its hints
    TAKE_CONTROL = "take_control"  # from another holder without asking
    SIMULATE = "simulate"  # run, pause, step, fast; snapshot a machine and restore it
    TEACH = "teach"  # classes and exercises, faults, broadcasts, the instructor's console
    MACHINES = "machines"  # create and delete machines
    USERS = "users"  # users, everyone's tokens, the service-wide audit


_OBSERVER = frozenset({Action.OBSERVE, Action.NOTE, Action.ASK, Action.TOKENS, Action.CAPTURE})
_OPERATOR = _OBSERVER | {
    Action.SHARE,
    Action.RECORD,
    Action.DELETE_TRACE,
    Action.PROGRAMS,
    Action.CONTROL,
    Action.STOP,
    Action.COMMAND,
    Action.CONFIGURE,
    Action.VERSIONS,
    Action.ASSIST,
    Action.SIGN_OFF,
    Action.EXERCISE,
}
_INSTRUCTOR = _OPERATOR | {Action.TAKE_CONTROL, Action.SIMULATE, Action.TEACH}

ALLOWED: dict[Role, frozenset[Action]] = {
    Role.OBSERVER: _OBSERVER,
    Role.OPERATOR: _OPERATOR,
    Role.INSTRUCTOR: _INSTRUCTOR,
    Role.ADMIN: frozenset(Action),
}
# each action in words, for the refusals people read (never the internal name)
ACTION_WORDS: dict[Action, str] = {
    Action.OBSERVE: "watch machines",
    Action.NOTE: "write in a machine's logbook",
    Action.ASK: "ask for control",
    Action.TOKENS: "make or revoke API tokens",
    Action.SHARE: "share a machine by link",
    Action.CAPTURE: "use the scope",
    Action.RECORD: "record channels to disk",
    Action.DELETE_TRACE: "delete traces",
    Action.PROGRAMS: "write or delete NC programs",
    Action.CONTROL: "take or hand over control",
    Action.STOP: "press the emergency stop",
    Action.COMMAND: "command the machine",
    Action.CONFIGURE: "write parameters",
    Action.VERSIONS: "take or delete parameter versions",
    Action.ASSIST: "run commissioning assistants",
    Action.SIGN_OFF: "sign a report off",
    Action.EXERCISE: "work on an exercise",
    Action.TAKE_CONTROL: "take control from its holder",
    Action.SIMULATE: "pace or snapshot the simulation",
    Action.TEACH: "run classes",
    Action.MACHINES: "create or delete machines",
    Action.USERS: "manage users",
}


def lowest_role(action: Action) -> Role:
    """The first role (observer … admin) that may do `action`."""
    return next(r for r in Role if action in ALLOWED[r])


HELD: frozenset[Action] = frozenset({Action.COMMAND, Action.CONFIGURE})
"""Actions on a machine that only its control holder may do (a free machine is taken by the
first of them)."""

SESSION_COOKIE = "inbetrieb_session"  # HttpOnly: the session, never readable by scripts
CSRF_COOKIE = "inbetrieb_csrf"  # readable by the page, which echoes it in CSRF_HEADER
CSRF_HEADER = "X-CSRF-Token"
CLIENT_HEADER = "X-Inbetrieb-Client"  # one browser tab: control is held by a tab, not a browser


class LoginRequest(BaseModel):
    """A name and password for `POST /api/auth/login`."""

    name: str = Field(min_length=1, max_length=64, description="user name")
    password: str = Field(min_length=1, max_length=256)


class SharedMachine(BaseModel):
    """The share link a guest came through: what they watch and until when."""

    machine: str
    label: str = Field(description="what the link's maker called it")
    expires_unix: float


class Me(BaseModel):
    """Who the request's session or token belongs to."""

    name: str
    role: Role
    session: str = Field(
        description="public id of this login session or API token (who holds control)"
    )
    actions: list[Action] = Field(description="what this user may do (api/auth.py ALLOWED)")
    guest: bool = Field(False, description="through a share link: watching one machine only")
    share: SharedMachine | None = Field(None, description="a guest's link (None: no guest)")
    watches: str | None = Field(
        None, description="a class's student: the machine their instructor presents, to watch"
    )


MIN_PASSWORD = 8  # characters (the CLI asks the same)
USER_NAME = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$"  # a path segment, a log entry's actor


class WsTicket(BaseModel):
    """Opens one telemetry websocket as this session: `?ticket=` on its URL (browsers cannot
    send headers on a websocket, and the session cookie alone is refused there)."""

    ticket: str
    expires_in_s: float = Field(description="good once, within this many seconds")


class TokenInfo(BaseModel):
    """An API token as anybody may see it: its public id, never the token itself."""

    id: str = Field(description="public id, as the audit trail and control name it")
    user: str
    label: str
    created_unix: float
    last_used_unix: float | None = Field(description="to within a minute; null: never used")


class TokenCreate(BaseModel):
    """A new API token of the requesting user."""

    label: str = Field(
        min_length=1, max_length=100, description="what it is for (shown in the list and audit)"
    )


class TokenCreated(BaseModel):
    """The new token: shown this once (the service keeps only its hash)."""

    token: str = Field(description="send as `Authorization: Bearer <token>`")
    info: TokenInfo


class UserInfo(BaseModel):
    name: str
    role: Role
    created_unix: float


class UserCreate(BaseModel):
    """A new user with a password."""

    name: str = Field(pattern=USER_NAME, description="letters, digits, _ . - (up to 64)")
    role: Role = Role.OPERATOR
    password: str = Field(min_length=MIN_PASSWORD, max_length=256)


class UserChange(BaseModel):
    """A new role and/or password (a new password ends the user's sessions)."""

    role: Role | None = None
    password: str | None = Field(None, min_length=MIN_PASSWORD, max_length=256)
