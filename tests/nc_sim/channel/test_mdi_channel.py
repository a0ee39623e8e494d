"""MDI blocks run through the channel (issue 16): a block's axes move on one path at the path
feed, modal words carry over from block to block, the spindle synchronises as in a program,
and the channel returns to where it was. Numbers from geometry and the demo's parameters."""

from __future__ import annotations

import numpy as np
import pytest

from nc_sim.commands import (
    Accepted,
    CycleStart,
    EmergencyStop,
    Mdi,
    ProgramLoad,
    Refused,
    Reset,
)
from nc_sim.errors import Code
from nc_sim.snapshot import ChannelState
from tests.nc_sim.sim_helpers import L, make, mdi, record

X0, Z0 = 50.0, -100.0  # where the demo lathe starts


def test_an_mdi_line_runs_both_axes_at_the_path_feed_and_they_arrive_together() -> None:
    """`G01 X90 Z-80 F600`: the path speed is 600 mm/min (not 600 per axis, 848 along the
    line), every point lies on the line, X and Z arrive in the same cycle."""
    sim, m, _ = make()
    x, z = m.axis("X"), m.axis("Z")
    mdi(m, "G01 X90 Z-80 F600")
    rec = record(sim, 8.0)
    px, pz = rec[:, x.slot, L.R_P_CMD], rec[:, z.slot, L.R_P_CMD]
    speed = np.hypot(rec[:, x.slot, L.R_V_CMD], rec[:, z.slot, L.R_V_CMD]) * 60.0
    assert speed.max() == pytest.approx(600.0, rel=1e-9)
    assert np.abs(20.0 * (px - X0) - 40.0 * (pz - Z0)).max() < 1e-9
    arrive_x = int(np.argmax(np.abs(px - 90.0) < 1e-9))
    arrive_z = int(np.argmax(np.abs(pz + 80.0) < 1e-9))
    assert arrive_x == arrive_z > 0
    assert m.queued_blocks == 0 and m.channel.state is ChannelState.IDLE


def test_a_bare_axis_word_after_g01_f500_moves_at_500_mm_min_not_at_rapid() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    mdi(m, "G01 X60 F500")
    record(sim, 3.0)
    mdi(m, "X70")
    rec = record(sim, 3.0)
    v = np.abs(rec[:, x.slot, L.R_V_CMD]) * 60.0
    assert v.max() == pytest.approx(500.0, rel=1e-9)  # rapid would be 8746 mm/min
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(70.0, abs=1e-9)
    modal = m.snapshot().channel.modal
    assert (modal.motion, modal.absolute, modal.feed_mm_min) == (1, True, 500.0)


def test_incremental_mdi_blocks_add_up_and_a_reset_sets_the_modal_words_back() -> None:
    sim, m, _ = make()
    x = m.axis("X")
    mdi(m, "G91 G01 X5 F1000")
    mdi(m, "X5")  # queued behind: 5 mm more from where the first ends
    record(sim, 3.0)
    assert m.k.st[x.slot, L.S_P_CMD] == pytest.approx(X0 + 10.0, abs=1e-9)
    m.submit(Reset())
    modal = m.snapshot().channel.modal
    assert (modal.motion, modal.absolute, modal.feed_mm_min) == (0, True, None)


def test_m3_with_a_move_holds_the_path_until_the_spindle_reached_its_speed() -> None:
    """000 §2.5.1: M3/M4/M5 always synchronise on speed reached, so `M3 S1000 G01 X60 F1000`
    moves X only after the spindle turns at 1000 rpm."""
    sim, m, cfg = make()
    x, s = m.axis("X"), m.axis("S1")
    band = cfg.axis("S1").eng("kenngr.vb_prozent")  # speed reached within this share
    mdi(m, "M3 S1000 G01 X60 F1000")
    record(sim, 0.1)
    # the demo's main spindle is S1: the status names it so, not "S"
    assert m.snapshot().channel.waiting_for == "speed reached of S1 (M3)"
    rec = record(sim, 6.0)
    first_x = int(np.argmax(np.abs(rec[:, x.slot, L.R_V_CMD]) > 0))
    reached = next(e.cycle for e in m.events if e.code == Code.EV_SPEED_REACHED and e.axis == "S1")
    assert first_x > 0 and first_x + sim.cycle - len(rec) >= reached
    assert abs(rec[first_x, s.slot, L.R_V_CMD]) >= 6000.0 * (1.0 - band)  # 1000 rpm = 6000 °/s


def test_mdi_shows_in_the_status_and_the_channel_returns_to_ready() -> None:
    sim, m, _ = make()
    assert isinstance(m.submit(ProgramLoad("p", "G01 X60 F500\nM30\n")), Accepted)
    mdi(m, "G01 Z-90 F600")
    ch = m.snapshot().channel
    assert ch.mdi and ch.state is ChannelState.RUNNING and ch.block_line is None
    refused = m.submit(CycleStart())
    assert isinstance(refused, Refused) and refused.code == Code.AXIS_BUSY
    record(sim, 2.0)
    ch = m.snapshot().channel
    assert not ch.mdi and ch.state is ChannelState.READY and ch.program == "p"
    done = [e.message for e in m.events if e.code == Code.EV_BLOCK_DONE]
    assert done == ["G01 Z-90 F600"]


def test_an_mdi_block_is_refused_while_a_program_runs() -> None:
    sim, m, _ = make()
    m.submit(ProgramLoad("p", "G01 X60 F300\nM30\n"))
    m.submit(CycleStart())
    record(sim, 0.1)
    out = m.submit(Mdi("G01 Z-90 F600"))
    assert isinstance(out, Refused) and out.code == Code.AXIS_BUSY


def test_an_emergency_stop_while_idle_keeps_the_modal_words_mdi_set() -> None:
    """G91 typed alone stays in force: an E-stop with nothing running ends no program, so
    nothing replaces MDI's modal words (only a reset sets them back)."""
    sim, m, _ = make()
    mdi(m, "G01 X60 F500")
    record(sim, 2.0)
    mdi(m, "G91")
    m.submit(EmergencyStop())
    modal = m.snapshot().channel.modal
    assert (modal.motion, modal.absolute, modal.feed_mm_min) == (1, False, 500.0)
