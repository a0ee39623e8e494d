"""The 003 §4.2 signals recorded every cycle (nc_sim.signals): the mode of the C-capable main
spindle, MVPOS/MVNEG and READY, under the configured name S1 whatever the mode."""

from __future__ import annotations

import numpy as np

from nc_sim.commands import JogStart, JogStop
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.signals import machine_signals, signal_columns
from nc_sim.units import RPM_TO_DEG_S
from tests.nc_sim.sim_helpers import L, make, mdi, record


def columns(m: Machine, rec: np.ndarray) -> dict[str, np.ndarray]:
    sigs = machine_signals(m.axes, m.channel_slot, m.rotary_spindle)
    return dict(zip((s.name for s in sigs), signal_columns(sigs, rec), strict=True))


def test_only_the_c_capable_spindle_records_its_mode_under_its_configured_name() -> None:
    _sim, m, _ = make()
    names = {s.name for s in machine_signals(m.axes, m.channel_slot, m.rotary_spindle)}
    assert m.rotary_spindle == "S1"
    assert "S1.rotary_mode" in names and not any(n.startswith("C.") for n in names)
    assert not any(n.endswith(".rotary_mode") for n in names - {"S1.rotary_mode"})
    for ax in ("X", "Z", "S1"):
        assert {f"{ax}.mvpos", f"{ax}.mvneg", f"{ax}.ready"} <= names


def test_rotary_mode_rises_in_the_cycle_after_the_rotary_mode_event() -> None:
    """#CAX: 0 up to the cycle in which the NC enters rotary axis mode (EV_ROTARY_MODE, 38,
    logged after that cycle's step), 1 from the next recorded cycle on."""
    sim, m, _ = make()
    seen = m.events.cursor
    mdi(m, "#CAX")
    rec = record(sim, 0.5)
    first = m.cycle - rec.shape[0] + 1  # the cycle of the record's first row
    (ev,) = [e for e in m.events.since(seen).entries if e.code == Code.EV_ROTARY_MODE]
    mode = columns(m, rec)["S1.rotary_mode"]
    i = ev.cycle - first
    assert 0 < i < rec.shape[0] - 1
    assert np.all(mode[: i + 1] == 0.0) and np.all(mode[i + 1 :] == 1.0)


def test_mvpos_and_mvneg_follow_the_sign_of_the_actual_speed_of_a_jog() -> None:
    """Jog C + then −: MVPOS while the actual speed exceeds one exact-stop window per second,
    MVNEG below its negative; neither at rest. READY throughout (enables and drive on)."""
    sim, m, _ = make()
    mdi(m, "#CAX")
    record(sim, 0.5)
    s1 = m.axis("S1")
    noise_deg_s = float(m.k.pr[s1.slot, L.P_INPOS_WIN])
    recs = []
    for direction in (1, -1):
        m.submit(JogStart("C", direction))
        recs.append(record(sim, 1.0))
        m.submit(JogStop("C"))
        recs.append(record(sim, 1.0))
    rec = np.concatenate(recs)
    c = columns(m, rec)
    v_deg_s = c["S1.speed_act_rpm"] * RPM_TO_DEG_S
    assert np.all(c["S1.rotary_mode"] == 1.0) and np.all(c["S1.ready"] == 1.0)
    np.testing.assert_array_equal(c["S1.mvpos"], v_deg_s > noise_deg_s)
    np.testing.assert_array_equal(c["S1.mvneg"], v_deg_s < -noise_deg_s)
    n = recs[0].shape[0]
    # half a second into each jog the axis moves at its jog speed; a second after the stop
    # it stands still
    assert c["S1.mvpos"][n // 2] == 1.0 and c["S1.mvneg"][n // 2] == 0.0
    assert c["S1.mvpos"][2 * n - 1] == 0.0 and c["S1.mvneg"][2 * n - 1] == 0.0
    assert c["S1.mvneg"][2 * n + n // 2] == 1.0 and c["S1.mvpos"][2 * n + n // 2] == 0.0
    assert c["S1.mvpos"][-1] == 0.0 and c["S1.mvneg"][-1] == 0.0
