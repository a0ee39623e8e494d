"""The program workspace in the browser: upload, save and list a program; a syntax error shown
at its line and column as one types (the mark exactly on that character); the draft kept across
workspaces and whether it is loaded; the tool path drawn; loading into the channel (and the
refusal of a bad program with its line and column); the New template runs; cycle start runs a
program, the actual path is drawn over the commanded one and starts anew with the next run;
the channel's state in the operator's words; the layout at 1920×1080 and 1024×768."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from playwright.sync_api import Browser, Locator, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import open_hmi, poll, shot

# a lathe program (Z across, X up): 4 motions, the arc a quarter of radius 5
TURN = "G18 G90\nG00 X40 Z5\nG01 Z-20 F300\nG02 X45 Z-25 K0 I5\nG00 X80 Z5\nM30\n"
# the commanded feed path is blue (#0b63b6, ToolpathPlot.tsx), also where smoothed into the
# white; grid, rapids (grey) and the actual path (red) are not
BLUE_OVER_RED = 50


def program_panel(page: Page) -> Locator:
    page.get_by_test_id("tab-Program").click()
    panel = page.get_by_test_id("panel-program")
    expect(panel).to_be_visible()
    return panel


def type_program(panel: Locator, text: str) -> None:
    panel.get_by_test_id("program-text").fill(text)


def feed_pixels(panel: Locator) -> int:
    """Pixels of the plot in the feed path's blue."""
    count: int = panel.get_by_test_id("toolpath-canvas").evaluate(
        """(c, k) => {
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          let n = 0;
          for (let i = 0; i < d.length; i += 4) if (d[i + 2] - d[i] > k) n++;
          return n;
        }""",
        BLUE_OVER_RED,
    )
    return count


def test_upload_save_and_list(page: Page, srv: Server, tmp_path: Path) -> None:
    panel = program_panel(page)
    f = tmp_path / "turn part#1.nc"
    f.write_text(TURN)
    panel.get_by_test_id("program-upload").set_input_files(str(f))
    expect(panel.get_by_test_id("program-name")).to_have_value("turn_part_1.nc")
    expect(panel.get_by_test_id("program-text")).to_have_value(TURN)
    panel.get_by_test_id("program-save").click()
    expect(panel.get_by_test_id("program-item-turn_part_1.nc")).to_be_visible()
    stored = srv.http.get("/api/programs/turn_part_1.nc").json()
    assert stored["text"] == TURN and stored["lines"] == 6
    # a new program, then the stored one opened again from the list
    panel.get_by_test_id("program-new").click()
    expect(panel.get_by_test_id("program-text")).not_to_have_value(TURN)
    panel.get_by_test_id("program-open-turn_part_1.nc").click()
    expect(panel.get_by_test_id("program-text")).to_have_value(TURN)
    # delete asks first
    panel.get_by_test_id("program-delete-turn_part_1.nc").click()
    panel.get_by_test_id("program-delete-confirm").click()
    expect(panel.get_by_test_id("program-item-turn_part_1.nc")).to_have_count(0)
    assert srv.http.get("/api/programs/turn_part_1.nc").status_code == 404


def test_a_syntax_error_is_shown_at_its_line_and_column(page: Page) -> None:
    panel = program_panel(page)
    type_program(panel, "G18\nG00 X40 Z5\nG01 Z-20 Q5 F300\nM30\n")  # Q: unknown address
    err = panel.get_by_test_id("program-error")
    expect(err).to_contain_text("line 3, column 10")
    expect(panel.get_by_test_id("program-error-line")).to_have_attribute("data-line", "3")
    type_program(panel, TURN)  # fixed: the mark goes
    expect(panel.get_by_test_id("program-ok")).to_contain_text("no errors: 4 moves")
    expect(panel.get_by_test_id("program-error-line")).to_have_count(0)


def test_the_tool_path_is_drawn(page: Page) -> None:
    panel = program_panel(page)
    type_program(panel, "G18\nM30\n")
    expect(panel.get_by_test_id("toolpath")).to_have_attribute("data-segments", "0")
    assert feed_pixels(panel) == 0
    type_program(panel, TURN)
    expect(panel.get_by_test_id("toolpath")).to_have_attribute("data-segments", "4")
    expect(panel.get_by_test_id("toolpath")).to_contain_text("G18: Z across, X up")
    page.wait_for_timeout(200)  # the next animation frame paints
    shot(page, "program-desktop")
    # the feed path (25 mm straight and a quarter of r = 5) fills the plot's width: many pixels
    assert feed_pixels(panel) > 100


def test_load_into_the_channel(page: Page, srv: Server, mid: str) -> None:
    panel = program_panel(page)
    type_program(panel, "G00 X10\nG01 Z5\nM30\n")  # no feed for G01: refused at line 2
    panel.get_by_test_id("program-name").fill("no_feed")
    panel.get_by_test_id("program-load").click()
    refusal = panel.get_by_test_id("program-refusal")
    expect(refusal).to_contain_text("line 2, column 1")
    assert srv.status(mid)["channel"]["program"] is None

    type_program(panel, TURN)
    panel.get_by_test_id("program-name").fill("turn_load.nc")
    panel.get_by_test_id("program-save").click()
    expect(panel.get_by_test_id("program-save")).to_have_text("Save")  # nothing unsaved
    panel.get_by_test_id("program-load").click()  # by name: the stored program
    expect(panel.get_by_test_id("channel-program")).to_have_text("turn_load.nc")
    expect(refusal).to_have_count(0)
    assert srv.status(mid)["channel"]["program"] == "turn_load.nc"


def test_tablet_layout(browser: Browser, srv: Server, mid: str) -> None:
    page = open_hmi(browser, srv.base, mid, size="tablet")
    try:
        panel = program_panel(page)
        type_program(panel, TURN)
        expect(panel.get_by_test_id("toolpath")).to_have_attribute("data-segments", "4")
        page.wait_for_timeout(200)
        assert feed_pixels(panel) > 100
        layout_checks(page, panel)
        shot(page, "program-tablet")
    finally:
        page.close()


def test_cycle_start_runs_the_program_and_draws_the_actual_path(
    page: Page, srv: Server, mid: str
) -> None:
    panel = program_panel(page)
    type_program(panel, TURN)
    panel.get_by_test_id("program-name").fill("turn_run.nc")
    panel.get_by_test_id("program-load").click()
    expect(panel.get_by_test_id("channel-program")).to_have_text("turn_run.nc")
    state = panel.get_by_test_id("channel-state")
    expect(state).to_have_text("Ready")
    panel.get_by_test_id("cycle-start").click()
    expect(state).to_have_text("Running")
    expect(panel.get_by_test_id("program-running-line")).to_be_visible()
    # M30: the program ends and stays loaded for the next cycle start
    expect(state).to_have_text("Program ended — ready", timeout=60_000)
    expect(state).to_have_attribute("data-state", "ready")
    # the axes ended where the program's last block sends them
    x, z = srv.axis("X", mid)["pos_cmd"], srv.axis("Z", mid)["pos_cmd"]
    assert abs(x - 80.0) < 1e-3 and abs(z - 5.0) < 1e-3
    shot(page, "program-ran-desktop")


def test_the_draft_survives_another_workspace_and_says_whether_it_is_loaded(
    page: Page, mid: str
) -> None:
    panel = program_panel(page)
    sync = panel.get_by_test_id("program-sync")
    type_program(panel, TURN)
    panel.get_by_test_id("program-name").fill("draft.nc")
    expect(sync).to_have_attribute("data-state", "none")
    page.get_by_test_id("tab-Operate").click()
    expect(panel).to_have_count(0)  # the workspace is gone, not hidden
    panel = program_panel(page)
    expect(panel.get_by_test_id("program-text")).to_have_value(TURN)
    expect(panel.get_by_test_id("program-name")).to_have_value("draft.nc")
    panel.get_by_test_id("program-load").click()
    expect(sync).to_have_attribute("data-state", "loaded")
    expect(sync).to_have_text("Loaded: draft.nc")
    # an edit: the channel still has the text as loaded
    type_program(panel, TURN.replace("F300", "F250"))
    expect(sync).to_have_attribute("data-state", "edited")
    expect(sync).to_contain_text("Edited — not loaded (the channel has draft.nc)")
    # the edit survives a switch too, and so does the knowledge of what was loaded
    page.get_by_test_id("tab-Plots").click()
    panel = program_panel(page)
    expect(panel.get_by_test_id("program-text")).to_have_value(TURN.replace("F300", "F250"))
    expect(sync).to_have_attribute("data-state", "edited")
    type_program(panel, TURN)  # back to the loaded text
    expect(sync).to_have_attribute("data-state", "loaded")


# the textarea's geometry, and the width of one character of its font measured in the page
TEXT_GEOMETRY = """t => {
  const cs = getComputedStyle(t);
  const probe = document.createElement('span');
  probe.style.font = cs.font;
  probe.style.whiteSpace = 'pre';
  probe.style.position = 'absolute';
  probe.textContent = '0'.repeat(100);
  document.body.appendChild(probe);
  const charW = probe.getBoundingClientRect().width / 100;
  probe.remove();
  const r = t.getBoundingClientRect();
  return {
    left: r.left + t.clientLeft + parseFloat(cs.paddingLeft) - t.scrollLeft,
    top: r.top + t.clientTop + parseFloat(cs.paddingTop) - t.scrollTop,
    lineH: parseFloat(cs.lineHeight), charW,
  };
}"""


def test_the_error_mark_sits_on_the_character_the_error_names(page: Page) -> None:
    panel = program_panel(page)
    # line 5, column 17: the Q (an unknown address) after 16 characters
    text = "G18 G90\nG00 X40 Z5\nG01 Z-20 F300\nG00 X80\nG01 X60 Z-20.25 Q5 F100\nM30\n"
    assert text.split("\n")[4].index("Q") == 16
    type_program(panel, text)
    expect(panel.get_by_test_id("program-error")).to_contain_text("line 5, column 17")
    g: dict[str, Any] = panel.get_by_test_id("program-text").evaluate(TEXT_GEOMETRY)
    box = panel.get_by_test_id("program-error-line-caret").bounding_box()
    assert box is not None
    row_top = g["top"] + 4 * g["lineH"]  # the fifth line's row
    assert row_top - 0.5 <= box["y"] and box["y"] + box["height"] <= row_top + g["lineH"] + 0.5, (
        box,
        g,
    )
    col_left = g["left"] + 16 * g["charW"]  # the 17th character
    assert abs(box["x"] - col_left) < 1.0, (box, g)
    assert abs(box["width"] - g["charW"]) < 1.0, (box, g)


def arcs_of(text: str) -> list[tuple[float, float]]:
    """Radius and half chord of every G02/G03 of a G18 G90 program (start from the block
    before; I/K centre offsets or R)."""
    pos = {"X": 0.0, "Z": 0.0}
    out: list[tuple[float, float]] = []
    for raw in text.splitlines():
        line = raw.split(";")[0].upper()
        words = dict((m[0], float(m[1:])) for m in re.findall(r"[A-Z]-?\d+(?:\.\d+)?", line))
        end = {a: words.get(a, pos[a]) for a in pos}
        if re.search(r"\bG0?[23]\b", line):
            half_chord = math.dist((pos["X"], pos["Z"]), (end["X"], end["Z"])) / 2
            if "R" in words:
                radius = abs(words["R"])
            else:
                centre = (pos["X"] + words.get("I", 0.0), pos["Z"] + words.get("K", 0.0))
                radius = math.dist((pos["X"], pos["Z"]), centre)
                # the end lies on the same circle
                assert abs(math.dist((end["X"], end["Z"]), centre) - radius) < 0.002, raw
            out.append((radius, half_chord))
        pos = end
    return out


def test_the_new_template_is_geometrically_sound_and_runs(
    page: Page, srv: Server, mid: str
) -> None:
    panel = program_panel(page)
    type_program(panel, "")
    panel.get_by_test_id("program-new").click()
    text = panel.get_by_test_id("program-text").input_value()
    arcs = arcs_of(text)
    assert arcs, "the template shows an arc"
    for radius, half_chord in arcs:
        assert radius >= half_chord, (radius, half_chord)
    expect(panel.get_by_test_id("program-ok")).to_contain_text("no errors")
    panel.get_by_test_id("program-load").click()
    expect(panel.get_by_test_id("program-sync")).to_have_attribute("data-state", "loaded")
    expect(panel.get_by_test_id("program-refusal")).to_have_count(0)
    panel.get_by_test_id("cycle-start").click()
    state = panel.get_by_test_id("channel-state")
    expect(state).to_have_text("Program ended — ready", timeout=60_000)
    assert srv.status(mid)["channel"]["error"] is None


def actual_from(panel: Locator) -> tuple[float, float] | None:
    """The first point of the actual path drawn (horizontal, vertical), None when empty."""
    v = panel.get_by_test_id("toolpath-canvas").get_attribute("data-actual-from") or ""
    return (float(v.split()[0]), float(v.split()[1])) if v else None


def test_a_new_run_starts_a_new_actual_path_a_resume_keeps_it(
    page: Page, srv: Server, mid: str
) -> None:
    panel = program_panel(page)
    state = panel.get_by_test_id("channel-state")
    # the demo lathe stands at X50 Z-100 (sim.start_pos); TURN ends at Z5 X80
    type_program(panel, TURN)
    panel.get_by_test_id("program-load").click()
    expect(panel.get_by_test_id("program-sync")).to_have_attribute("data-state", "loaded")
    panel.get_by_test_id("cycle-start").click()
    expect(state).to_have_text("Program ended — ready", timeout=60_000)
    first = actual_from(panel)
    assert first is not None and math.dist(first, (5.0, 80.0)) > 50, first  # near the start
    # the second run starts where the first ended: the old trace is dropped (the run is
    # seen starting by the status, so the trace starts within a few status periods of
    # feed, 10 mm/s, from Z5 X80)
    type_program(panel, "G18 G90\nG01 Z-25 F600\nG01 Z5\nM30\n")
    panel.get_by_test_id("program-load").click()
    expect(panel.get_by_test_id("program-sync")).to_have_attribute("data-state", "loaded")
    panel.get_by_test_id("cycle-start").click()
    expect(state).to_have_attribute("data-state", "running")
    poll(
        lambda: (p := actual_from(panel)) is not None and math.dist(p, (5.0, 80.0)) < 3.0,
        "the new run's path to start at Z5 X80",
    )
    second = actual_from(panel)
    # feedhold and cycle start continue the run: the trace keeps its start
    panel.get_by_test_id("feedhold").click()
    expect(state).to_have_text("Feedhold")
    panel.get_by_test_id("feedhold").click()  # release the hold, then continue
    panel.get_by_test_id("cycle-start").click()
    expect(state).to_have_text("Program ended — ready", timeout=60_000)
    assert actual_from(panel) == second


def test_states_in_operator_words_and_the_spindle_by_its_name(
    page: Page, srv: Server, mid: str
) -> None:
    spindle = next(a["name"] for a in srv.status(mid)["axes"] if a["kind"] == "spindle")
    assert spindle != "S"  # the demo lathe calls its spindle S1
    panel = program_panel(page)
    state = panel.get_by_test_id("channel-state")
    expect(state).to_have_text("No program (MDI)")
    type_program(panel, "G18 G90\nG01 Z-98 F600\nM3 S1200\nG01 Z-96\nM5\nM30\n")
    panel.get_by_test_id("single-block").click()
    panel.get_by_test_id("program-load").click()
    expect(state).to_have_text("Ready")
    panel.get_by_test_id("cycle-start").click()
    expect(state).to_have_text("Block end (single block)")
    expect(state).to_have_attribute("data-state", "block_end")
    panel.get_by_test_id("single-block").click()
    panel.get_by_test_id("cycle-start").click()
    # M3 S1200: the path waits for speed reached of the spindle, named as the machine names it
    waiting = panel.get_by_test_id("channel-waiting")
    expect(waiting).to_contain_text("speed reached", timeout=10_000)
    words = waiting.inner_text()
    assert spindle in words and not re.search(r"\bS\b", words), words
    expect(panel.get_by_text(spindle, exact=True)).to_be_visible()  # the speed readout's label
    expect(state).to_have_text("Program ended — ready", timeout=60_000)


def layout_checks(page: Page, panel: Locator) -> None:
    """The workspace fits the page's width; editor, channel and plot do not overlap; the
    channel's buttons stand in one row, each label on one line."""
    widths = page.evaluate("[document.documentElement.scrollWidth, innerWidth]")
    assert widths[0] <= widths[1], widths
    boxes = {
        k: panel.get_by_test_id(k).bounding_box()
        for k in ("program-text", "channel", "toolpath-canvas", "program-list")
    }
    for k, box in boxes.items():
        assert box is not None and box["width"] > 100 and box["x"] + box["width"] <= widths[1], (
            k,
            box,
        )
    names = list(boxes)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            p, q = boxes[a], boxes[b]
            assert p is not None and q is not None
            apart = (
                p["x"] + p["width"] <= q["x"]
                or q["x"] + q["width"] <= p["x"]
                or p["y"] + p["height"] <= q["y"]
                or q["y"] + q["height"] <= p["y"]
            )
            assert apart, (a, p, b, q)
    buttons = panel.get_by_test_id("channel").locator(".channel-buttons button")
    rows = buttons.evaluate_all(
        """bs => bs.map(b => {
          const r = b.getBoundingClientRect(), lh = parseFloat(getComputedStyle(b).lineHeight);
          return [r.top, b.clientHeight - parseFloat(getComputedStyle(b).paddingTop)
                  - parseFloat(getComputedStyle(b).paddingBottom), lh];
        })"""
    )
    assert len(rows) == 5
    assert max(r[0] for r in rows) - min(r[0] for r in rows) < 1, rows  # one row
    assert all(r[1] < 1.5 * r[2] for r in rows), rows  # one line of label each


def test_desktop_layout(page: Page) -> None:
    panel = program_panel(page)
    type_program(panel, TURN)
    layout_checks(page, panel)
