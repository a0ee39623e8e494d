"""Commissioning assistants (nc_sim/assist, by their descriptors in registry.py): on a copy
of a machine — its parameters as the gateway holds them — an experiment runs in simulated
time in a process of its own (so neither the gateway's event loop nor a worker's real-time
loop waits for it), a calculator at once; live, the machine's worker paces the run. The answer
is the API model; Apply is a parameter write.
"""

from __future__ import annotations

import asyncio
import copy
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from typing import Any

from pydantic import BaseModel

from api.assist import AssistResult
from backend.errors import Invalid, TimedOut, Unavailable
from backend.services.audit import Audit
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.machines import MachineProxy
from backend.workers.protocol import AssistCancel, AssistStart
from nc_sim.assist.result import ExperimentError
from nc_sim.assist.run import run
from nc_sim.config import MachineConfig
from nc_sim.faults import Fault
from nc_sim.training.dry_run import DryRun, dry_run
from nc_sim.training.exercise import Exercise

RUN_TIMEOUT_S = 120.0  # an experiment ends in simulated time long before this


class ExperimentRefused(Exception):
    """The experiment cannot run as asked (raised in the assistants' process, re-raised
    here: an exception pickles across the process pool)."""


def _run(
    name: str, cfg: MachineConfig, args: dict[str, Any], faults: list[Fault]
) -> dict[str, Any]:
    """In the assistants' process: run one experiment on a copy carrying `faults`; its
    answer (ExperimentRefused when it cannot run). The kernel is imported here, in that
    process: the gateway itself never loads it."""
    try:
        return run(name, cfg, args, faults).as_json()
    except ExperimentError as e:
        raise ExperimentRefused(str(e)) from None


def calculate(cfg: MachineConfig, name: str, req: BaseModel) -> AssistResult:
    """Calculator `name` on the request's inputs (pure arithmetic, no kernel: answered in the
    gateway), its changes with the machine's values before; Invalid with the calculator's
    reason when the inputs do not fit together."""
    try:
        return AssistResult.model_validate(run(name, cfg, req.model_dump()).as_json())
    except ExperimentError as e:
        raise Invalid(str(e)) from None  # the route names the calculator


def _dry(exercise: Exercise, seconds: float) -> DryRun:
    """In the assistants' process: an exercise's seat run untouched (the kernel loads there)."""
    return dry_run(exercise, seconds)


class Assistants:
    """One process for the assistants' runs, started on the first and kept (a queue of one);
    an exercise's dry run goes there too."""

    def __init__(self) -> None:
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            ctx = multiprocessing.get_context("spawn")  # no copy of the gateway's threads
            self._pool = ProcessPoolExecutor(max_workers=1, mp_context=ctx)
        return self._pool

    async def run(
        self, cfg: MachineConfig, name: str, req: BaseModel, faults: list[Fault]
    ) -> AssistResult:
        """Run experiment `name` with the arguments of `req` on a copy of `cfg` with the
        machine's training `faults` in force; 422 when it cannot run."""
        args = req.model_dump()
        loop = asyncio.get_running_loop()
        fut = loop.run_in_executor(
            self._executor(), _run, name, copy.deepcopy(cfg), args, list(faults)
        )
        try:
            answer = await asyncio.wait_for(fut, RUN_TIMEOUT_S)
        except TimeoutError:
            why = f"the {name} experiment did not end within {RUN_TIMEOUT_S:g} s"
            raise TimedOut(why) from None
        except ExperimentRefused as e:
            raise Invalid(f"{name}: {e}") from None
        return AssistResult.model_validate(answer)

    async def dry_run(self, exercise: Exercise, seconds: float) -> DryRun:
        """`exercise`'s seat run untouched for `seconds` of simulated time on a copy."""
        loop = asyncio.get_running_loop()
        fut = loop.run_in_executor(self._executor(), _dry, exercise, seconds)
        try:
            return await asyncio.wait_for(fut, RUN_TIMEOUT_S)
        except TimeoutError:
            raise TimedOut(f"the dry run did not end within {RUN_TIMEOUT_S:g} s") from None

    def stop(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)


LIVE_TIMEOUT_S = 600.0  # a paused machine holds a live run: after this it is cancelled


async def run_live(
    machine: MachineProxy, name: str, req: BaseModel, actor: Actor, audit: Audit
) -> AssistResult:
    """Run assistant `name` live on the machine itself, paced by its worker (real time, fast
    or stepped alike); answered when it ends. Audited as the commands it gives."""
    args = req.model_dump()
    detail = {"assistant": name, **args}
    entry = Entry(actor.name, actor.session, "assist", f"assist live {name}", machine.id, detail)
    start = AssistStart(machine.id, name, args, actor.name)
    with audit.refusals(entry):
        try:
            answer = await machine.link.acall(start, LIVE_TIMEOUT_S)
        except Unavailable:  # no answer in time: the run must not go on unattended
            machine.link.post(AssistCancel(machine.id, "the run did not end in time"))
            raise
    assert isinstance(answer, dict)
    result = AssistResult.model_validate(answer)
    figures = {f.name: round(f.value, 6) for f in result.figures}
    audit.record(replace(entry, detail={**detail, "figures": figures}))
    return result


async def cancel_live(machine: MachineProxy, why: str, actor: Actor, audit: Audit) -> None:
    """End the machine's live run now (409 when none runs)."""
    entry = Entry(actor.name, actor.session, "assist", "assist live cancel", machine.id)
    with audit.refusals(entry):
        await machine.link.acall(AssistCancel(machine.id, f"{why} ({actor.name})"))
    audit.record(entry)
