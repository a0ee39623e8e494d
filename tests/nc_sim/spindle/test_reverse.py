"""P-AXIS-00159 getriebe[i].reverse [000]: "If reverse is TRUE, the signs of the output and
input data are changed" for that gear stage: the spindle turns the other way while the NC
sees its setpoint and actual value as before."""

from __future__ import annotations

import numpy as np
import pytest

from tests.nc_sim.sim_helpers import L, make, mdi, record

RPM = 6.0  # °/s per rpm
NO_PLC = {"spindel[0].m3_synch": 0, "spindel[0].m5_synch": 0}


def _turn(reverse: dict[int, int], blocks: list[str], seconds: float) -> tuple[np.ndarray, int]:
    params = {f"getriebe[{g}].reverse": v for g, v in reverse.items()}
    sim, m, _cfg = make({"S1": params}, NO_PLC)
    s = m.axis("S1").slot
    recs = []
    for block in blocks:
        mdi(m, block)
        recs.append(record(sim, seconds))
    return np.concatenate(recs), s


@pytest.mark.parametrize("reverse", [0, 1])
def test_a_reversed_gear_stage_turns_the_spindle_the_other_way_as_the_nc_sees_it_alike(
    reverse: int,
) -> None:
    rec, s = _turn(dict.fromkeys(range(6), reverse), ["M3 S500"], 3.0)
    # the NC: M3 S500, reached, as without reverse
    assert rec[-1, s, L.R_V_ACT] / RPM == pytest.approx(500.0, rel=0.05)
    assert rec[-1, s, L.R_SPEED_REACHED] == 1
    # the drive: the output's sign changed, and so the way it turns
    out = np.sign(rec[-1, s, L.R_DA])
    assert out == (-1.0 if reverse else 1.0)


def test_a_gear_change_into_a_reversed_stage_keeps_the_nc_position() -> None:
    # reverse only in gear record 1 (M41, stage 2): from M40 (record 0) into it at standstill
    rec, s = _turn({1: 1}, ["M40 M3 S300", "M5", "M41 M3 S700"], 3.0)
    p = rec[:, s, L.R_P_ACT]
    v = rec[:, s, L.R_V_ACT]
    # no jump of the actual position beyond what the speed moves it in a cycle
    step = np.abs(np.diff(p))
    step = np.minimum(step, 360.0 - step)  # modulo 360°
    assert (step <= np.abs(v[1:]) * 0.001 + 1.0).all()
    assert rec[-1, s, L.R_V_ACT] / RPM == pytest.approx(700.0, rel=0.05)
    assert rec[-1, s, L.R_GEAR] == 2 and np.sign(rec[-1, s, L.R_DA]) == -1.0
