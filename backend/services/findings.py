"""A seat's answers to its exercise's finding checks: kept with the seat's progress (they
survive restarts of the machine and the service), graded against what the seat's machine
hides (nc_sim/training/findings.py), each attempt counted."""

from __future__ import annotations

from api.classes import AnswerGiven, FindingAnswer, FindingState
from api.machines import MachineLists
from backend.errors import Conflict, Invalid, not_found
from nc_sim.config import MachineConfig, machine_from_lists
from nc_sim.errors import NcUsageError
from nc_sim.training.checks import Check, FindingCheck
from nc_sim.training.exercise import Exercise
from nc_sim.training.findings import grade, unit_of
from nc_sim.training.template import seat_config

Answers = dict[str, list[AnswerGiven]]  # check id -> the answers given, in order


def seat_machine(ex: Exercise, lists: MachineLists | None) -> MachineConfig:
    """The seat's machine as the exercise starts it (the class's lists or the demo lathe)."""
    template = None
    if lists is not None:
        template = machine_from_lists("seat", lists.channel_list, lists.axis_lists, lists.tool_list)
    return seat_config(ex, template)


def finding_of(check: Check) -> FindingCheck | None:
    return check.rule if isinstance(check.rule, FindingCheck) else None


def state(rule: FindingCheck, cfg: MachineConfig, given: list[AnswerGiven]) -> FindingState:
    """What the student sees of a finding: the axes to choose from and the answers so far."""
    axes = [a.name for a in cfg.axes]
    return FindingState(
        fault=rule.fault,
        axes=axes,
        units=[unit_of(cfg, a) for a in axes],
        attempts_left=max(0, rule.attempts - len(given)),
        answers=list(given),
    )


def answer(ex: Exercise, cfg: MachineConfig, answers: Answers, req: FindingAnswer) -> AnswerGiven:
    """Grade one answer and keep it in `answers`: 404 for a check the exercise lacks, 422 for
    a check that is not a finding or an axis the machine lacks, 409 once the attempts are used
    or the finding is already right."""
    check = next((c for c in ex.checks if c.id == req.check), None)
    if check is None:
        raise not_found(f"check '{req.check}' of exercise '{ex.id}'")
    rule = finding_of(check)
    if rule is None:
        raise Invalid(f"check '{req.check}' is measured on the machine, not answered")
    given = answers.setdefault(req.check, [])
    if any(a.passed for a in given):
        raise Conflict(f"check '{req.check}' is answered and right: nothing more to answer")
    if len(given) >= rule.attempts:
        raise Conflict(f"check '{req.check}': all {rule.attempts} attempts are used")
    try:
        graded = grade(rule, (f.fault for f in ex.faults), cfg, req.axis, req.value)
    except NcUsageError:
        names = ", ".join(a.name for a in cfg.axes)
        raise Invalid(f"axis: '{req.axis}' is not an axis of the machine ({names})") from None
    out = AnswerGiven(axis=req.axis, value=req.value, passed=graded.passed, detail=graded.detail)
    given.append(out)
    return out
