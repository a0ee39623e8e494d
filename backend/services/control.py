"""One operator per machine: who holds control, who asks for it, and when it lapses.

The state lives on each machine's proxy (`m.control`) and changes only here, under one lock.
Every change is audited and pushed with the machine's status (its `seq` makes the telemetry
hub send the status again at once). When control changes hands the old holder's jogs stop:
a held jog belongs to its holder's session.
"""

from __future__ import annotations

import asyncio
import threading
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from api.auth import ALLOWED, Action
from api.control import REQUEST_S, ControlAction, ControlParty, ControlState
from backend.errors import ApiError, Conflict, Forbidden, NotFound
from backend.services.audit import Audit
from backend.services.audit_log import Entry
from backend.services.auth import Actor, authorize
from backend.tasks import cancel
from backend.workers.protocol import Request, Submit
from nc_sim import commands as nc

SWEEP_S = 0.5  # how often lapsed holders and requests are looked for
Key = tuple[str, str]  # (session, client)


@dataclass
class MachineControl:
    """Control of one machine (kept on its machine's proxy)."""

    holder: ControlParty | None = None
    requests: list[ControlParty] = field(default_factory=list)
    connections: Counter[Key] = field(default_factory=Counter)  # live websockets per client
    watching: dict[Key, ControlParty] = field(default_factory=dict)  # who those clients are
    release_at: float | None = None  # wall time: the holder has no connection since
    # changes, for the pushed status; from the wall clock in ms, so that a page left open
    # across a restart of the service takes the new state as newer
    seq: int = field(default_factory=lambda: int(time.time() * 1000))
    frozen_by: str | None = None  # a class seat frozen by this instructor: students wait

    def state(self) -> ControlState:
        lost = self.holder is not None and self.release_at is not None
        return ControlState(
            holder=self.holder,
            requests=list(self.requests),
            connected=not lost,
            release_at_unix=self.release_at if lost else None,
            seq=self.seq,
            viewers=list(self.watching.values()),
        )


def _key(p: ControlParty | Actor) -> Key:
    return p.session, p.client


def _party(actor: Actor) -> ControlParty:
    return ControlParty(
        user=actor.name,
        role=actor.role,
        session=actor.session,
        client=actor.client,
        since_unix=time.time(),
        guest=actor.guest,
    )


class Link(Protocol):
    """What control needs of a machine's worker link (`MachineLink` is one)."""

    @property
    def axes(self) -> list[str]: ...

    def post(self, request: Request) -> None: ...


class Controlled(Protocol):
    """What control needs of a machine (`MachineProxy` is one)."""

    id: str
    control: MachineControl

    @property
    def link(self) -> Link: ...


class Machines(Protocol):
    """What control needs of the machines (`Machines` is one)."""

    def proxies(self) -> Sequence[Controlled]: ...


def _who(p: ControlParty) -> str:
    return f"{p.user} ({p.role.value})"


class Control:
    """Takes, requests, grants and releases control of every machine."""

    def __init__(self, machines: Machines, audit: Audit, grace_s: float) -> None:
        self.machines = machines
        self.audit = audit
        self.grace_s = grace_s
        self._lock = threading.Lock()
        self._task: asyncio.Task[None] | None = None

    @staticmethod
    def _not_frozen(actor: Actor, m: Controlled) -> None:
        """409 for a class's student on their seat while the instructor has it frozen."""
        by = m.control.frozen_by
        if by is not None and actor.seat is not None:
            raise Conflict(f"{by} froze {m.id}: you act on it again once they resume it")

    # --- asked by every action only a holder may do ----------------------------------------
    def hold(self, actor: Actor, m: Controlled) -> None:
        """Pass if the actor holds the machine (taking it when free); 403 naming the holder
        otherwise, 409 for a student while their seat is frozen."""
        with self._lock:
            self._not_frozen(actor, m)
            c = m.control
            if c.holder is None:
                self._change(m, _party(actor), actor, "took control of a free machine")
                return
            if _key(c.holder) == _key(actor):
                if not c.connections[_key(actor)]:  # a script's request keeps it alive
                    c.release_at = time.time() + self.grace_s
                    c.seq += 1
                return
            holder = c.holder
        if holder.session == actor.session:
            elsewhere = " in another tab"
        elif holder.user == actor.name:  # the same person through a browser and a token
            elsewhere = " in another session (a browser or an API token): release it there"
        else:
            elsewhere = ""
        raise Forbidden(
            f"control of {m.id} is held by {_who(holder)}{elsewhere}: request it to act"
        )

    # --- the control route ------------------------------------------------------------------
    def act(self, actor: Actor, m: Controlled, req: ControlAction) -> ControlState:
        """Carry out a take, request, cancel, grant, refuse or release; the state after it."""
        with self._lock:
            self._act(actor, m, req)
            return m.control.state()

    def _act(self, actor: Actor, m: Controlled, req: ControlAction) -> None:
        c = m.control
        mine = c.holder is not None and _key(c.holder) == _key(actor)
        if req.action in ("take", "request"):
            self._not_frozen(actor, m)
        # observers ask, never hold; a guest or a student watching a presentation neither
        if req.action not in ("request", "cancel") or actor.guest or actor.watches == m.id:
            authorize(actor, Action.CONTROL, m.id)
        match req.action:
            case "take":
                if mine:
                    return
                if c.holder is not None and c.holder.session != actor.session:
                    try:
                        authorize(actor, Action.TAKE_CONTROL, m.id)
                    except ApiError:
                        raise Forbidden(
                            f"control of {m.id} is held by {_who(c.holder)}: "
                            "request it (only an instructor or admin takes it)"
                        ) from None
                was = f" from {_who(c.holder)}" if c.holder else ""
                self._change(m, _party(actor), actor, f"took control{was}")
            case "request":
                if c.holder is None and Action.CONTROL not in ALLOWED[actor.role]:
                    raise Conflict("nobody holds the machine: there is nobody to ask")
                if mine or c.holder is None:
                    raise Conflict(
                        "nothing to request: take the free machine"
                        if c.holder is None
                        else "you hold control already"
                    )
                if all(_key(r) != _key(actor) for r in c.requests):
                    text = (req.message or "").strip()
                    asker = _party(actor)
                    lapses = asker.since_unix + REQUEST_S
                    c.requests.append(
                        asker.model_copy(update={"message": text, "lapses_unix": lapses})
                    )
                    said = f": “{text}”" if text else ""
                    self._changed(m, actor, f"requested control from {_who(c.holder)}{said}")
            case "cancel":
                before = len(c.requests)
                c.requests = [r for r in c.requests if _key(r) != _key(actor)]
                if len(c.requests) != before:
                    self._changed(m, actor, "withdrew the request for control")
            case "grant" | "refuse":
                if not mine:
                    raise Forbidden(f"only the holder may {req.action} control")
                asked = [
                    r for r in c.requests if (r.session, r.client) == (req.session, req.client)
                ]
                if not asked:
                    raise NotFound("no such request (withdrawn or lapsed)")
                c.requests.remove(asked[0])
                if req.action == "refuse":
                    watcher = Action.COMMAND not in ALLOWED[asked[0].role]
                    what = "answered the request of" if watcher else "refused control to"
                    self._changed(m, actor, f"{what} {_who(asked[0])}")
                elif Action.COMMAND not in ALLOWED[asked[0].role]:
                    c.requests.append(asked[0])  # still asking: the holder may refuse it
                    raise Conflict(
                        f"{_who(asked[0])} may watch only: control would not let them command "
                        "(an admin can make them an operator)"
                    )
                else:
                    to = asked[0].model_copy(update={"since_unix": time.time()})
                    self._change(m, to, actor, f"granted control to {_who(to)}")
            case "release":
                if mine:
                    self._change(m, None, actor, "released control")

    # --- connections, sessions, lapse -------------------------------------------------------
    def connected(self, actor: Actor, m: Controlled) -> None:
        """A websocket of this client watches the machine."""
        with self._lock:
            c = m.control
            c.connections[_key(actor)] += 1
            if _key(actor) not in c.watching:
                c.watching[_key(actor)] = _party(actor)
                c.seq += 1
            if c.holder is not None and _key(c.holder) == _key(actor) and c.release_at:
                c.release_at = None
                c.seq += 1

    def disconnected(self, actor: Actor, m: Controlled) -> None:
        """One of its websockets closed; the last one starts the grace period of a holder."""
        with self._lock:
            c = m.control
            c.connections[_key(actor)] -= 1
            if c.connections[_key(actor)] <= 0:
                del c.connections[_key(actor)]
                c.watching.pop(_key(actor), None)
                c.seq += 1
                if c.holder is not None and _key(c.holder) == _key(actor):
                    c.release_at = time.time() + self.grace_s
                    c.seq += 1

    def end_session(self, session: str, why: str) -> None:
        """The session ended (logout, expiry, removal): its control and requests go."""
        with self._lock:
            for m in self.machines.proxies():
                c = m.control
                before = len(c.requests)
                c.requests = [r for r in c.requests if r.session != session]
                if len(c.requests) != before:
                    c.seq += 1
                if c.holder is not None and c.holder.session == session:
                    self._lapse(m, f"control released: {why}")

    def sweep(self, now: float | None = None) -> None:
        """Release the control of holders whose connection is gone longer than the grace
        period, and drop requests nobody answered."""
        now = time.time() if now is None else now
        with self._lock:
            for m in self.machines.proxies():
                c = m.control
                lapsed = c.release_at is not None and now >= c.release_at
                if c.holder is not None and lapsed:
                    self._lapse(m, f"control released: no connection for {self.grace_s:g} s")
                fresh = [r for r in c.requests if now - r.since_unix < REQUEST_S]
                if len(fresh) != len(c.requests):
                    c.requests = fresh
                    c.seq += 1

    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self._run())

    async def stop(self) -> None:
        await cancel(self._task)

    async def _run(self) -> None:
        while True:
            await asyncio.sleep(SWEEP_S)
            self.sweep()

    # --- changes (holding the lock) ---------------------------------------------------------
    def _lapse(self, m: Controlled, why: str) -> None:
        holder = m.control.holder
        assert holder is not None
        actor = Actor(holder.user, holder.role, holder.session, holder.client)
        self._change(m, None, actor, why)

    def _change(self, m: Controlled, to: ControlParty | None, by: Actor, what: str) -> None:
        """A new holder (or none): the old holder's jogs stop, the change is audited."""
        c = m.control
        old = c.holder
        c.holder = to
        c.release_at = None
        if to is not None:
            c.requests = [r for r in c.requests if _key(r) != _key(to)]
            if not c.connections[_key(to)]:  # a script, or a tab whose socket is gone
                c.release_at = time.time() + self.grace_s
        if old is not None:
            for axis in m.link.axes:  # a jog lease of the old holder must not outlive it
                m.link.post(Submit(m.id, nc.JogStop(axis), None, True, []))
        self._changed(
            m, by, what, {"from": old.user if old else None, "to": to.user if to else None}
        )

    def _changed(
        self, m: Controlled, by: Actor, what: str, detail: dict[str, object] | None = None
    ) -> None:
        m.control.seq += 1
        self.audit.record_later(  # the event loop may be here: never wait for the disk
            Entry(
                actor=by.name,
                session=by.session,
                kind="control",
                action=what,
                machine=m.id,
                detail=detail or {},
            )
        )
