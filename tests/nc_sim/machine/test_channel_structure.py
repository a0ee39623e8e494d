"""The channel list's structure entries [000 §2.2]: which axis lists become which path axes
(achse[i].bezeichnung / log_achs_nr), how many spindles there are and what they are called
(spdl_anzahl, spindel[i].bezeichnung / log_achs_nr), which of them is the main spindle
(main_spindle_ax_nr) and the name S words address it by (main_spindle_name)."""

from __future__ import annotations

import re

import pytest

from nc_sim.commands import Accepted, Mdi
from nc_sim.config import demo_lists, machine_from_lists
from nc_sim.errors import NcUsageError
from nc_sim.sim import Simulation
from tests.nc_sim.sim_helpers import L, record


def _channel(changes: dict[str, str]) -> str:
    """The demo channel list with these entries replaced."""
    text, _axes = demo_lists()
    for key, value in changes.items():
        text, n = re.subn(rf"(?m)^{re.escape(key)}\s+\S+", f"{key} {value}", text)
        assert n == 1, key
    return text


def test_axes_and_the_spindle_take_the_names_and_lists_the_channel_gives() -> None:
    # the Z list (logical axis 2) as W, the spindle as S4: names from the channel list
    text = _channel({"achse[1].bezeichnung": "W", "spindel[0].bezeichnung": "S4"})
    _t, axes = demo_lists()
    cfg = machine_from_lists("renamed", text, axes)
    assert [a.name for a in cfg.axes] == ["X", "W", "S4"]
    assert cfg.main_spindle == "S4"  # main_spindle_ax_nr 3 = spindel[0].log_achs_nr
    sim = Simulation(cfg.cycle_s)
    m = sim.add(cfg)
    sim.run(20)
    # main_spindle_name S: "S" and "M3" address the main spindle, whatever its name
    assert isinstance(m.submit(Mdi("M3 S300")), Accepted)
    assert isinstance(m.submit(Mdi("G01 W-90 F600")), Accepted)
    rec = record(sim, 8.0)
    assert rec[-1, m.axis("S4").slot, L.R_V_CMD] == pytest.approx(300 * 6.0)
    assert rec[-1, m.axis("W").slot, L.R_P_CMD] == pytest.approx(-90.0)


def test_achse_log_achs_nr_chooses_the_axis_list_an_axis_takes() -> None:
    # X on list 2 and Z on list 1: each starts where its list's sim.start_pos puts it
    _t, axes = demo_lists()
    text = _channel({"achse[0].log_achs_nr": "2", "achse[1].log_achs_nr": "1"})
    cfg = machine_from_lists("swapped", text, axes)
    x, z = cfg.axis("X"), cfg.axis("Z")
    assert x.values["sim.start_pos"] == -1000000  # list 2's: -100 mm
    assert z.values["sim.start_pos"] == 500000  # list 1's: 50 mm


def test_a_channel_without_spindles_has_none() -> None:
    _t, axes = demo_lists()
    cfg = machine_from_lists("no spindle", _channel({"spdl_anzahl": "0"}), axes)
    assert [a.name for a in cfg.axes] == ["X", "Z"] and cfg.main_spindle is None


def test_a_channel_naming_an_axis_without_a_list_is_refused() -> None:
    _t, axes = demo_lists()
    with pytest.raises(NcUsageError, match="log_achs_nr 7"):
        machine_from_lists("bad", _channel({"spindel[0].log_achs_nr": "7"}), axes)
