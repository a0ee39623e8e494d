"""Event and job-error codes: every code has its own meaning in words, each kind of event its
own code, and the user guide's tables (docs/user-guide.md) list them all."""

from __future__ import annotations

import re
from pathlib import Path

from nc_sim.commands import Accepted, Mdi, SpindleRun
from nc_sim.errors import MESSAGES, Code
from tests.nc_sim.sim_helpers import make, record

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "user-guide.md"


def test_every_code_has_a_message_in_words() -> None:
    for code in Code:
        msg = MESSAGES[code]  # KeyError: a code without a message
        # words, not the enum's name ("ev motion done", "EV_MOTION_DONE")
        assert msg and not msg.lower().startswith("ev ") and code.name not in msg, (code, msg)


def test_an_event_without_detail_reads_as_its_meaning() -> None:
    sim, m, _ = make()
    assert isinstance(m.submit(Mdi("G91 G01 X1 F600")), Accepted)
    record(sim, 1.0)
    done = [e for e in m.events if e.code == Code.EV_MOTION_DONE]
    assert [e.message for e in done] == [MESSAGES[Code.EV_MOTION_DONE]] and done[0].axis == "X"
    assert done[0].message.startswith("motion done")


def test_a_gear_change_is_not_logged_as_an_hli_write() -> None:
    sim, m, _ = make()
    # the demo starts in M42: 300 rpm needs M40
    assert isinstance(m.submit(SpindleRun("S", 3, 300)), Accepted)
    record(sim, 3.0)
    hli = [e for e in m.events if e.code == Code.EV_HLI]
    started = [e for e in m.events if e.code == Code.EV_GEAR_CHANGE_START]
    assert hli == []
    # gear stages by the M function that selects them, as the HMI names them (stage g: M39+g)
    assert [e.message for e in started] == ["S1 gear change M42 -> M40"]
    changed = [e.message for e in m.events if e.code == Code.EV_GEAR_CHANGED]
    assert changed == ["S1 gear M42 -> M40"]  # and it completed


def test_the_user_guides_tables_list_every_code() -> None:
    text = GUIDE.read_text(encoding="utf-8")
    documented = {int(c) for c in re.findall(r"^\| (\d+) \|", text, flags=re.M)}
    assert {int(c) for c in Code} <= documented, sorted({int(c) for c in Code} - documented)
