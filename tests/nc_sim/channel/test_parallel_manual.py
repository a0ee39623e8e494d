"""G201, manual mode with parallel path interpolation [002 §2.6.2]: while the program's path
moves an axis it may be jogged on top of it, the jog with its share of the axis' dynamics
(hb_proz_a_max P-AXIS-00082, hb_proz_v_max P-AXIS-00083 of P-AXIS-00008 and P-AXIS-00212),
the path with the rest (ipo_proz_a_max P-AXIS-00094, ipo_proz_v_max P-AXIS-00095). G200, the
default, keeps a path axis to the path.

The demo lathe's X: P-AXIS-00212 vb_max 500 mm/s, P-AXIS-00008 a_max 5000 mm/s², G01
a_beschl 2000 mm/s²; the shares are the manual's excerpt (30 % manual, 70 % path) unless a
test sets its own."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    CycleStart,
    JogStart,
    JogStep,
    JogStop,
    ProgramLoad,
    Refused,
)
from nc_sim.config import apply_overrides, demo_machine
from nc_sim.errors import Code
from nc_sim.machine.machine import Machine
from nc_sim.params import Scope
from nc_sim.params.listfile import ParamListError
from nc_sim.sim import Simulation
from nc_sim.snapshot import AxisState, ChannelState
from tests.nc_sim.sim_helpers import L, make, record

# the manual's excerpt of the axis list for G201 (hb.tr 50000 µs)
EXCERPT = {
    "handbetrieb.hb.tr": 50000,
    "handbetrieb.ipo.hb_proz_v_max": 30,
    "handbetrieb.ipo.hb_proz_a_max": 30,
    "handbetrieb.ipo.ipo_proz_v_max": 70,
    "handbetrieb.ipo.ipo_proz_a_max": 70,
}
VB_MAX, A_MAX = 500.0, 5000.0  # the demo's X: P-AXIS-00212 (mm/s), P-AXIS-00008 (mm/s²)


def _start(program: str, x: dict[str, Any] | None = None) -> tuple[Simulation, Machine]:
    sim, m, _cfg = make({"X": {**EXCERPT, **(x or {})}})
    assert isinstance(m.submit(ProgramLoad("g201", program)), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    return sim, m


def _x(rec: np.ndarray, m: Machine) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = m.axis("X").slot
    return rec[:, s, L.R_P_CMD], rec[:, s, L.R_V_CMD], rec[:, s, L.R_A_CMD]


def test_the_path_keeps_its_share_of_speed_and_acceleration() -> None:
    """F30000 asks for 500 mm/s: G201 leaves the path 70 % of P-AXIS-00212, and with a_beschl
    at P-AXIS-00008 (5000 mm/s²) 70 % of that. G200 gives the path all of it."""
    x = {"getriebe[0].slope_profil.a_beschl": 5000}
    for g, v_top, a_top in (("G200", VB_MAX, A_MAX), ("G201", 0.7 * VB_MAX, 0.7 * A_MAX)):
        sim, m = _start(f"N10 {g}\nN20 G01 X400 F30000\nN30 M30\n", x)
        _p, v, a = _x(record(sim, 2.5), m)
        assert v.max() == pytest.approx(v_top, rel=1e-6), g
        assert a.max() == pytest.approx(a_top, rel=1e-6), g


def test_a_jog_step_rides_on_the_path_with_the_manual_share() -> None:
    """X steps 40 mm while Z runs a 300 mm line (X is on the path, standing on it): X's
    speed never goes above 30 % of 500 mm/s nor its acceleration above 30 % of 5000 mm/s²,
    and it ends 40 mm on."""
    sim, m = _start("N10 G201\nN20 G91 G01 Z-300 F6000\nN30 M30\n")
    record(sim, 0.5)  # the path runs (Z at 100 mm/s)
    x0 = m.k.st[m.axis("X").slot, L.S_P_CMD]
    assert isinstance(m.submit(JogStep("X", 40.0)), Accepted)
    p, v, a = _x(record(sim, 3.0), m)
    # 40 mm reach the top speed: 150²/1500 mm to speed up and brake, 7.5 mm more for ramps
    assert v.max() == pytest.approx(0.3 * VB_MAX, rel=1e-6)
    assert a.max() == pytest.approx(0.3 * A_MAX, rel=1e-6)
    assert p[-1] == pytest.approx(x0 + 40.0, abs=1e-9)
    assert m.channel.state is ChannelState.READY  # the program ran to its end
    assert m.axis("X").state is AxisState.STANDSTILL


def test_a_jog_adds_its_speed_to_the_path_axis_it_rides_on() -> None:
    """X runs G01 at 10 mm/s; a jog on X in the same direction at 1200 mm/min adds 20 mm/s:
    the axis runs at 30 mm/s while both move, and ends where both put it."""
    sim, m = _start("N10 G201\nN20 G91 G01 X100 F600\nN30 M30\n")
    x0 = m.k.st[m.axis("X").slot, L.S_P_CMD]
    record(sim, 1.0)
    assert isinstance(m.submit(JogStart("X", 1, feed_mm_min=1200)), Accepted)
    _p, v, _a = _x(record(sim, 1.0), m)
    assert v[-1] == pytest.approx(30.0, rel=1e-6)
    assert isinstance(m.submit(JogStop("X")), Accepted)
    record(sim, 0.5)
    jogged = m.k.st[m.axis("X").slot, L.S_MAN_P]
    assert 20.0 < jogged < 21.0  # about a second at 20 mm/s, with its ramps
    record(sim, 12.0)
    assert m.k.st[m.axis("X").slot, L.S_P_CMD] == pytest.approx(x0 + 100.0 + jogged, abs=1e-9)


def test_a_jog_that_outlasts_the_program_goes_on_as_a_jog_of_its_own() -> None:
    sim, m = _start("N10 G201\nN20 G91 G01 Z-10 F600\nN30 M30\n")
    record(sim, 0.2)
    assert isinstance(m.submit(JogStart("X", -1, feed_mm_min=600)), Accepted)
    record(sim, 2.0)  # the 10 mm of Z took a second: the program has ended
    x = m.axis("X")
    assert m.channel.state is ChannelState.READY
    assert x.state is AxisState.JOG
    assert m.k.st[x.slot, L.S_V_CMD] == pytest.approx(-10.0)  # 600 mm/min, without a jump
    assert isinstance(m.submit(JogStop("X")), Accepted)
    record(sim, 0.5)
    assert m.axis("X").state is AxisState.STANDSTILL
    assert m.k.st[x.slot, L.S_V_CMD] == 0.0


def test_without_g201_a_path_axis_is_not_jogged() -> None:
    sim, m = _start("N10 G91 G01 X20 Z-300 F6000\nN20 M30\n")
    x0 = m.k.st[m.axis("X").slot, L.S_P_CMD]
    record(sim, 0.5)
    outcome = m.submit(JogStep("X", 5.0))
    assert isinstance(outcome, Refused) and outcome.code == Code.AXIS_BUSY
    assert "G201" in outcome.detail
    p, _v, _a = _x(record(sim, 4.0), m)
    assert p[-1] == pytest.approx(x0 + 20.0, abs=1e-9)


def test_a_new_program_starts_in_g200() -> None:
    """G201 holds until the next start or reset [002 §2.6]: the next program may not be
    jogged. The status says which is in force."""
    sim, m = _start("N10 G201\nN20 G91 G01 Z-5 F6000\nN30 M30\n")
    record(sim, 1.0)
    assert m.snapshot().channel.modal.parallel_manual
    assert isinstance(m.submit(ProgramLoad("next", "N10 G91 G01 Z-300 F6000\nN20 M30\n")), Accepted)
    assert isinstance(m.submit(CycleStart()), Accepted)
    record(sim, 0.3)
    assert not m.snapshot().channel.modal.parallel_manual
    outcome = m.submit(JogStep("Z", 1.0))
    assert isinstance(outcome, Refused) and outcome.code == Code.AXIS_BUSY


def test_shares_above_the_whole_limit_are_refused_naming_them() -> None:
    """Manual and path share split one limit: 60 % + 70 % of P-AXIS-00212 would exceed it."""
    cfg = demo_machine()
    with pytest.raises(ParamListError) as e:
        apply_overrides(cfg, Scope.AXIS, "X", {"handbetrieb.ipo.hb_proz_v_max": 60})
    assert "handbetrieb.ipo.hb_proz_v_max" in str(e.value) and "130 %" in str(e.value)
    apply_overrides(cfg, Scope.AXIS, "X", {"handbetrieb.ipo.hb_proz_v_max": 30})  # 30 + 70
