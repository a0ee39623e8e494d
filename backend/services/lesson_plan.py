"""A class's lesson plan: its exercises in order, each seat moving on by itself (its student,
once every check of the exercise has passed) or by the instructor. Moving on keeps the
exercise's result and powers the seat's machine on afresh for the next one: the template's
parameters with its starting values, its faults with the seat's own numbers, its checks, a new
start snapshot, the clock from 0."""

from __future__ import annotations

import time

from api.auth import ALLOWED, Action
from backend.errors import ApiError, Conflict, Forbidden
from backend.services.auth import Actor
from backend.services.classes import Classes
from backend.services.seats import Class, Seat, start_values
from backend.workers.protocol import Mode
from nc_sim.training.variation import seat_seed


def may_move_on(actor: Actor, c: Class, seat: Seat) -> ApiError | None:
    """Why the asker may not move the seat on to the plan's next exercise now (None: they
    may): an instructor at any time, its student once every check has passed."""
    if c.ended_unix is not None:
        return Conflict(f"class '{c.id}' has ended")
    if seat.stage + 1 >= len(c.plan):
        return Conflict(f"seat {seat.n} is at the plan's last exercise")
    if Action.TEACH in ALLOWED[actor.role]:
        return None
    if actor.name != seat.user:
        return Forbidden(f"only seat {seat.n}'s student or an instructor moves it on")
    missing = [k.id for k in seat.exercise.checks if k.id not in seat.first_passed_s]
    if missing:
        return Conflict(
            f"check{'s' if len(missing) > 1 else ''} {', '.join(missing)} not passed yet: "
            "the instructor can move you on"
        )
    return None


def move_on(classes: Classes, actor: Actor, c: Class, seats: list[Seat]) -> None:
    """Each seat to the plan's next exercise (none when one of them may not: its error):
    its result in the exercise kept, its machine powered on afresh with the next one's
    starting values (its parameters as the template has them otherwise), faults with the
    seat's own numbers and checks, a new start snapshot, a clock from 0."""
    for seat in seats:
        refusal = may_move_on(actor, c, seat)
        if refusal is not None:
            raise refusal
    for seat in seats:
        _move_on(classes, actor, c, seat)


def _move_on(classes: Classes, actor: Actor, c: Class, seat: Seat) -> None:
    proxy = classes.machines.get(seat.machine)
    classes.update(seat, proxy)
    by = seat.student if actor.name == seat.user else actor.name  # a name, not a login
    done = classes.stage_result(c, seat, by, time.time())
    stage = seat.stage + 1
    plan_ex = c.plan[stage]
    ex, values = plan_ex.for_seat(seat_seed(c.id, plan_ex.id), seat.n)
    changes, entries = start_values(actor, seat.machine, ex)
    classes.store.replace_values(seat.machine, changes, entries)
    classes.faults.forget(seat.machine)
    what = f"exercise {stage + 1} of {len(c.plan)}, '{ex.title}'"
    mode: Mode = "pause" if seat.frozen or seat.joined_unix is None else "run"
    faults = [(f.fault, f.trigger) for f in ex.faults]
    proxy = classes.machines.restage(seat.machine, ex, faults, f"{what}: {actor.name}", mode)
    with classes.lock:  # from here on the new build's status counts, from its time 0
        seat.done.append(done)
        seat.stage, seat.exercise, seat.values = stage, ex, values
        seat.hints, seat.answers = set(), {}  # a raised hand stays up: not seen to yet
        seat.first_passed_s, seat.passed, seat.detail = {}, {}, {}
        seat.first_detail = {}
        seat.time_base_s, seat.last_t_s = 0.0, 0.0
        seat.epoch, seat.epoch_start_s = proxy.link.epoch, 0.0
    classes.save(seat)
    classes.faults.keep(proxy)
    classes.snapshots.forget(seat.machine)  # the last exercise's: restored, they would mix
    classes.snapshots.take(actor, proxy, f"start of exercise {stage + 1}", pinned=True)
    proxy.notices.add("exercise", f"{by} moved the seat on to {what}")
    classes.audit.record(
        classes.entry(actor, f"moved seat {seat.n} on to {what}", seat.machine, score=done.score)
    )
