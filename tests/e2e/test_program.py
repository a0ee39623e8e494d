"""The program workspace in the browser: upload, save and list a program; a syntax error shown
at its line and column as one types; the tool path drawn; loading into the channel (and the
refusal of a bad program with its line and column); cycle start runs it and the actual path is
drawn over the commanded one."""

from __future__ import annotations

import re
from pathlib import Path

from playwright.sync_api import Browser, Locator, Page, expect

from tests.backend.server import Server
from tests.e2e.browser import open_hmi, shot

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
    expect(panel.get_by_test_id("channel-state")).to_have_text("ready")
    panel.get_by_test_id("cycle-start").click()
    expect(panel.get_by_test_id("channel-state")).to_have_text("running")
    expect(panel.get_by_test_id("program-running-line")).to_be_visible()
    # M30: the program ends and stays loaded for the next cycle start
    state = panel.get_by_test_id("channel-state")
    expect(state).to_have_text(re.compile("ready|idle"), timeout=60_000)
    # the axes ended where the program's last block sends them
    x, z = srv.axis("X", mid)["pos_cmd"], srv.axis("Z", mid)["pos_cmd"]
    assert abs(x - 80.0) < 1e-3 and abs(z - 5.0) < 1e-3
    shot(page, "program-ran-desktop")
