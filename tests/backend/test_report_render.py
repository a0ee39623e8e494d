"""The report's sections rendered from data (issue 39's report frictions): a sweep's figures
as one table, whether a proposal is in force, the simulated plant apart from the NC's
parameters, every channel of a trace plotted."""

from __future__ import annotations

import re

from api.assist import AssistChange, AssistFigure, AssistResult
from api.report import AssistRun
from backend.report import html
from backend.report.runs import runs_section


def _run(figures: list[AssistFigure], changes: list[AssistChange]) -> AssistRun:
    result = AssistResult(
        assistant="loop-gain",
        ok=True,
        inputs={"axis": "X"},
        figures=figures,
        changes=changes,
        series=[],
        notes=[],
    )
    return AssistRun(
        id=7,
        machine="m",
        assistant="loop-gain",
        user="ana",
        time_unix=0.0,
        live=False,
        ok=True,
        axis="X",
        summary="",
        result=result,
    )


def test_a_sweeps_figures_read_as_one_table_over_the_swept_value() -> None:
    """Ten kv values, two figures each: ten rows (sorted by kv), two columns, not 20 rows."""
    kvs = [5.0 * (i + 1) for i in range(10)]
    figures = [AssistFigure(name="kv_best", value=20.0, unit="1/s")]
    for kv in reversed(kvs):
        figures.append(AssistFigure(name=f"lag_overshoot_pct@{kv:g}", value=kv / 10, unit="%"))
        figures.append(AssistFigure(name=f"settling_s@{kv:g}", value=1 / kv, unit="s"))
    text = runs_section([_run(figures, [])], 0, {})
    rows = re.findall(r'<tr data-sweep="([^"]+)">(.*?)</tr>', text)
    assert [float(at) for at, _ in rows] == kvs
    cells = re.findall(r"<td[^>]*>(.*?)</td>", rows[1][1])
    assert cells == ["10", "1", "0.1"]
    assert "lag_overshoot_pct [%]" in text and "settling_s [s]" in text
    assert 'data-figure="kv_best"' in text and 'data-figure="lag_overshoot' not in text


def test_a_proposal_says_whether_it_is_in_force_now() -> None:
    changes = [
        AssistChange(target="X", parameter="getriebe[0].multi_gain_z", before=10000, after=22857),
        AssistChange(target="X", parameter="getriebe[0].kv", before=2000, after=875),
    ]
    now: dict[tuple[str, str], object] = {
        ("X", "getriebe[0].multi_gain_z"): 22857,
        ("X", "getriebe[0].kv"): 2000,
    }
    text = runs_section([_run([], changes)], 0, now)
    rows = re.findall(r"<tr><td>X</td>(.*?)</tr>", text)
    assert "in force now" in rows[0] and "not applied" in rows[1]


def _row(parameter: str, before: object, after: object) -> html.BaselineRow:
    return html.BaselineRow("X", parameter, "", before, after, "", "")


def _data(**kw: object) -> html.ReportData:
    base: dict[str, object] = dict(
        machine=html.MachineFacts("m", "M", "demo lathe", [("X", "linear")]),
        generated_unix=0.0,
        generated_by="ana",
        commissioners=[],
        runs=[],
        runs_left_out=0,
        baseline=None,
        traces=[],
        audit=[],
        audit_total=0,
        audit_commands=0,
        sign_offs=[],
        in_force={},
    )
    base.update(kw)
    return html.ReportData(**base)  # type: ignore[arg-type]


def test_the_simulated_plant_is_listed_apart_from_the_ncs_parameters() -> None:
    rows = [_row("getriebe[0].kv", 2000, 2500), _row("sim.drive_gain", 10000, 22857)]
    text = html.render(_data(baseline=rows))
    nc, plant = text.split('id="plant-changes"')
    assert 'data-parameter="X.getriebe[0].kv"' in nc and "sim.drive_gain" not in nc
    assert 'data-parameter="X.sim.drive_gain"' in plant
    assert "1 parameters differ" in nc


def test_every_channel_of_a_trace_is_plotted_one_plot_per_quantity() -> None:
    t = [i * 0.001 for i in range(50)]
    trace = html.TracePlot(
        id="tr",
        name="X at 1 m/min",
        notes="",
        created_unix=0.0,
        trigger="forced",
        t_s=t,
        channels=[
            html.TraceChannel("X.lag_mm", "mm", [0.8] * 50),
            html.TraceChannel("X.pos_act_mm", "mm", t),
            html.TraceChannel("X.pos_cmd_mm", "mm", t),
            html.TraceChannel("X.vel_cmd_mm_min", "mm/min", [1000.0] * 50),
        ],
    )
    text = html.render(_data(traces=[trace]))
    article = text.split('data-trace="tr"')[1]
    assert article.count("<svg") == 3  # the lag, the positions, the speed: each its own axis
    assert article.count("<polyline") == 4
    assert "X.pos_act_mm, X.pos_cmd_mm</figcaption>" in article
    assert ">X.lag_mm</figcaption>" in article
