"""NC programs: the stored ones (by name, every write audited) and the preview of a program's
tool path on a machine (interpreted here: the interpreter is pure, no kernel needed).

Programs are service-wide, except a class's student's: a student writes, replaces and deletes
the programs of their seat only (nobody else sees them), and reads those and the service-wide
ones (the exercise's, written by the instructor); their own comes first by a name they share.
"""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime
from typing import Literal

from fastapi.concurrency import run_in_threadpool

from api.programs import PreviewError, PreviewSegment, Program, ProgramInfo, ProgramPreview
from backend.errors import Forbidden, not_found
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.store import Store, StoredProgram
from nc_sim.channel import canon
from nc_sim.channel.interpreter import interpret
from nc_sim.channel.preview import preview
from nc_sim.channel.words import ProgramError
from nc_sim.snapshot import MachineSnapshot
from nc_sim.units import AxisKind

_PLANE: dict[int, Literal["G17", "G18", "G19"]] = {17: "G17", 18: "G18", 19: "G19"}


def owners(actor: Actor) -> tuple[str, ...]:
    """Whose programs the actor reads, first match first: a student's seat, then everyone's."""
    return ("",) if actor.seat is None else (actor.seat, "")


def program_info(p: StoredProgram) -> ProgramInfo:
    return ProgramInfo(
        name=p.name,
        size=p.size,
        lines=p.lines,
        updated_at=datetime.fromtimestamp(p.updated, UTC),
        updated_by=p.updated_by,
        seat=p.owner or None,
    )


def program_of(p: StoredProgram) -> Program:
    return Program(**program_info(p).model_dump(), text=p.text)


def listed(store: Store, actor: Actor) -> list[ProgramInfo]:
    """The programs the actor reads, by name (without their text)."""
    return [program_info(p) for p in store.programs(owners(actor))]


def get(store: Store, actor: Actor, name: str) -> StoredProgram:
    """The stored program `name` (any case) the actor reads; 404 without one."""
    p = store.program(name, owners(actor))
    if p is None:
        raise not_found(f"program {name}")
    return p


def put(store: Store, actor: Actor, name: str, text: str) -> ProgramInfo:
    """Create or replace a program of the actor's (a student's: of their seat), audited with
    its size (the text is in the store)."""
    owner = actor.seat or ""
    before = store.program(name, (owner,))
    verb = "replaced" if before is not None else "created"
    where = f" of seat {owner}" if owner else ""
    entry = Entry(
        actor.name,
        actor.session,
        "program",
        f"{verb} program {name}{where} ({len(text)} characters)",
        machine=owner,
        detail={"name": name, "size": len(text), "lines": len(text.splitlines())},
    )
    return program_info(store.put_program(name, text, entry, owner))


def delete(store: Store, actor: Actor, name: str) -> None:
    """Delete a program of the actor's (audited); 404 without one, 403 for a student and a
    service-wide program."""
    owner = actor.seat or ""
    where = f" of seat {owner}" if owner else ""
    entry = Entry(
        actor.name,
        actor.session,
        "program",
        f"deleted program {name}{where}",
        machine=owner,
        detail={"name": name},
    )
    if store.delete_program(name, entry, owner):
        return
    if owner and store.program(name, ("",)) is not None:
        why = f"{actor.name} may delete only the programs of their seat, not the shared {name}"
        raise Forbidden(why)
    raise not_found(f"program {name}")


def stored_text(store: Store, actor: Actor, name: str) -> str:
    """The text of a stored program the actor reads, for `program_load` without a text; 404
    without one."""
    return get(store, actor, name).text


# a preview may interpret up to MAX_PROGRAM_BLOCKS blocks (seconds, tens of MB): a few at a
# time, the others wait their turn
PREVIEWS_AT_ONCE = 2
_previews = asyncio.Semaphore(PREVIEWS_AT_ONCE)


async def program_preview_off_loop(snapshot: MachineSnapshot, text: str) -> ProgramPreview:
    """`program_preview` on the thread pool, at most PREVIEWS_AT_ONCE at a time."""
    async with _previews:
        return await run_in_threadpool(program_preview, snapshot, text)


def program_preview(snapshot: MachineSnapshot, text: str) -> ProgramPreview:
    """The program's commanded tool path on this machine from its commanded positions, up to
    its first error."""
    ch = snapshot.channel
    axes = list(ch.axes)
    spindles = [a.name for a in snapshot.axes if a.kind is AxisKind.SPINDLE]
    start = {a.name: a.pos_cmd for a in snapshot.axes if a.kind is not AxisKind.SPINDLE}
    c = ch.rotary_axis
    if c is not None:  # C from where the rotary axis is; 0 in the drawing while a spindle
        start[c] = next(
            (a.pos_cmd for a in snapshot.axes if a.display_name == c and ch.rotary), 0.0
        )
    sink = canon.ListSink()
    error = None
    try:
        interpret(text, sink, axes, spindles, start, c_axis=c, rotary=ch.rotary)
    except ProgramError as e:
        error = PreviewError(line=e.line, column=e.column, code=int(e.code), message=e.detail)
    p = preview(sink.calls, start, axes)
    return ProgramPreview(
        error=error,
        plane=_PLANE[p.plane],
        axes=p.axes,
        segments=[PreviewSegment(line=s.line, rapid=s.rapid, points=s.points) for s in p.segments],
        truncated=p.truncated,
    )
