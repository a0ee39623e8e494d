"""Commissioning assistants: multi_gain by experiment and the sign check (on a copy or live),
the curve run-up and the position loop gain sweep (on copies), the calculators and the
gear-range preview."""

from __future__ import annotations

from fastapi import APIRouter
from pydantic import BaseModel

from api.assist import (
    AssistResult,
    CurveFitRequest,
    CurveRunUpRequest,
    GearSelectionRequest,
    GearSelectionResult,
    LiveCancel,
    LoopGainRequest,
    MultiGainCalcRequest,
    MultiGainRequest,
    ResolutionRequest,
    SignCheckRequest,
    SpeedScalingRequest,
)
from api.auth import Action
from backend.deps import ActorDep, MachineDep, Services, ServicesDep, permit
from backend.errors import (
    NO_CONTENT,
    Conflict,
    Forbidden,
    Invalid,
    NotFound,
    TimedOut,
    Unavailable,
    Why,
    responses,
)
from backend.services.assist import cancel_live, run_live
from backend.services.auth import Actor
from backend.services.calculators import calculate, gear_selection
from backend.services.machines import MachineProxy

router = APIRouter(prefix="/api/machines/{mid}/assist", tags=["assistants"])
_WHY: Why = {
    Invalid: "the experiment cannot run as asked (no feed, unknown axis, refused motion)",
    TimedOut: "the experiment did not end in time",
}


async def _on_copy(
    name: str, body: BaseModel, machine: MachineProxy, services: Services, actor: Actor
) -> AssistResult:
    """Experiment `name` on a copy of the machine, stored for the report."""
    result = await services.assistants.run(machine.cfg, name, body)
    await services.assist_runs.record(machine.id, actor.name, result, live=False)
    return result


async def _live(
    name: str, body: BaseModel, machine: MachineProxy, services: Services, actor: Actor
) -> AssistResult:
    """Experiment `name` on the machine itself, stored for the report."""
    result = await run_live(machine, name, body, actor, services.audit)
    await services.assist_runs.record(machine.id, actor.name, result, live=True)
    return result


@router.post(
    "/multi-gain",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_WHY),
)
async def multi_gain(
    body: MultiGainRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """004 §3.6.2 on a copy of the machine with its parameters now, in simulated time: the
    axis at constant feed (a spindle at constant speed, position-controlled), the averaged
    lag, k = v/s, f = (kv/100)/k and the proposed multi_gain · f and kv / f. The live machine
    does not move; Apply is a parameter write. Stored (GET .../assist/runs)."""
    return await _on_copy("multi-gain", body, machine, services, actor)


@router.post(
    "/sign-check",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_WHY),
)
async def sign_check(
    body: SignCheckRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """004 §3.5 on a copy of the machine: a short slow move; a wrong sign of the manipulated
    variable (vz_stellgr) or of the actual value (vz_istw) is found before lag monitoring
    trips, from the way the machine moved (`observed`, else the simulated plant's). Stored."""
    return await _on_copy("sign-check", body, machine, services, actor)


@router.post(
    "/loop-gain",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_WHY),
)
async def loop_gain(
    body: LoopGainRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """004 §3.6 on copies of the machine, one per kv: a G00 step (overshoot, settling into the
    exact-stop window) and a G01 ramp (steady lag v/kv); the highest kv meeting the target
    is proposed as getriebe[g].kv. The live machine does not move. Stored."""
    return await _on_copy("loop-gain", body, machine, services, actor)


@router.post(
    "/curve-run-up",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_WHY),
)
async def curve_run_up(
    body: CurveRunUpRequest, machine: MachineDep, services: ServicesDep, actor: ActorDep
) -> AssistResult:
    """000 §2.8.4 on a copy of the machine: the spindle runs up with M3 in the gear to its
    top speed (the gear's vb_max, or `speed_rpm`) at the acceleration its parameters allow;
    a(n) from the recorded actual speed, the curve of type `typ` fitted by least squares and
    proposed as the gear's beschl_kennlinie. Stored."""
    return await _on_copy("curve-run-up", body, machine, services, actor)


# The calculators: pure arithmetic, answered in the request (a thread of the pool, not the
# assistants' process: no kernel, no simulation). The machine supplies the values "before".
_CALC_WHY: Why = {
    Invalid: "the inputs do not fit together (which one, and why) or the axis is unknown"
}


@router.post(
    "/resolution",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def resolution(body: ResolutionRequest, machine: MachineDep) -> AssistResult:
    """004 §3.4: wegaufz/wegaufn = encoder increments per motor revolution over the distance
    one motor revolution moves the axis (pitch / i in 0.1 µm, or 360° / i in 0.0001°)."""
    return calculate(machine.cfg, "resolution", body)


@router.post(
    "/multi-gain-calc",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def multi_gain_calc(body: MultiGainCalcRequest, machine: MachineDep) -> AssistResult:
    """004 §3.6.1: multi_gain = f · n, the command value per motor rpm f (from the drive's
    scaling) times the motor speed n for 1 m/min (1000 °/min rotary) with the gear i."""
    return calculate(machine.cfg, "multi-gain-calc", body)


@router.post(
    "/speed-scaling",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def speed_scaling(body: SpeedScalingRequest, machine: MachineDep) -> AssistResult:
    """000 §2.2.4: v_reso_num/v_reso_denom = increments over the distance (0.001°) the
    spindle covers at that speed in the time base (P-AXIS-00207)."""
    return calculate(machine.cfg, "speed-scaling", body)


@router.post(
    "/curve-fit",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def curve_fit(body: CurveFitRequest, machine: MachineDep) -> AssistResult:
    """000 §2.8.4: the coefficients of the spindle gear's acceleration curve (types 1, 2, 3)
    through 3-4 interpolation points, or by least squares through more."""
    return calculate(machine.cfg, "curve-fit", body)


@router.post(
    "/gear-ranges",
    dependencies=[permit(Action.ASSIST)],
    responses=responses(NotFound, Invalid, why=_CALC_WHY),
)
def gear_ranges(body: GearSelectionRequest, machine: MachineDep) -> GearSelectionResult:
    """000 §2.8.2: the main spindle's six speed ranges (as edited, else the machine's), the
    stage the NC's automatic selection picks for each S in turn, and the edited ranges as
    parameter changes (spindel[i].range_table[j].min_speed / max_speed)."""
    return gear_selection(machine.cfg, body)


_LIVE_WHY: Why = {
    Conflict: "another assistant runs, the run was cancelled (E-stop, cancel) or the machine "
    "rebuilt",
    Invalid: "the NC refused the run's motion (not ready, limits, busy) or bad inputs",
    Unavailable: "the machine has no worker now, or the run did not end in time (then it is "
    "cancelled)",
}


@router.post(
    "/live/multi-gain",
    dependencies=[permit(Action.COMMAND)],
    responses=responses(Forbidden, NotFound, Conflict, Invalid, Unavailable, why=_LIVE_WHY),
)
async def multi_gain_live(
    body: MultiGainRequest, machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> AssistResult:
    """004 §3.6.2 on the machine itself, as paced (real time, fast or stepped): the axis
    moves (the spindle turns) for the run's planned time, which the machine's status shows
    as `assist` with its phase while it runs. Needs control of the machine."""
    return await _live("multi-gain", body, machine, services, actor)


@router.post(
    "/live/sign-check",
    dependencies=[permit(Action.COMMAND)],
    responses=responses(Forbidden, NotFound, Conflict, Invalid, Unavailable, why=_LIVE_WHY),
)
async def sign_check_live(
    body: SignCheckRequest, machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> AssistResult:
    """004 §3.5 on the machine itself: the short move, watched cycle by cycle; a runaway
    switches the servo off (TorquePermission 0) in the cycle it is seen. Needs control."""
    return await _live("sign-check", body, machine, services, actor)


@router.post(
    "/live/cancel",
    status_code=NO_CONTENT,
    dependencies=[permit(Action.STOP)],
    responses=responses(
        Forbidden, NotFound, Conflict, why={Conflict: "no assistant runs on the machine"}
    ),
)
async def cancel(
    body: LiveCancel, machine: MachineDep, actor: ActorDep, services: ServicesDep
) -> None:
    """End the machine's live run now: an axis brakes as at a CNC reset, a spindle stops
    (M5). Like the emergency stop, any operator may, holding control or not."""
    await cancel_live(machine, body.why, actor, services.audit)
