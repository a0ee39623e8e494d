"""The assistant runs in the report: each run's inputs, figures (a sweep's as one table over
its swept value), the changes it proposed with whether they are in force now, its plots."""

from __future__ import annotations

import re

from api.assist import AssistSeries
from api.report import AssistRun
from backend.report import polar, svg
from backend.report.text import assistant_title, e, number, table, when

MAX_LINES = 4  # series in one plot before they are split by name
MAX_LEVELS = 3  # reference levels drawn on one plot


def _run_plot(run: AssistRun) -> str:
    """One plot per pair of units: series over the same quantities share it (measured
    points and their fit); a crowd of them is split by name (step@10 … and ramp_lag@10 …)."""
    groups: dict[tuple[str, str, str], list[AssistSeries]] = {}
    by_units: dict[tuple[str, str], list[AssistSeries]] = {}
    for s in run.result.series:
        by_units.setdefault((s.x_unit, s.y_unit), []).append(s)
    for (x_unit, y_unit), series in by_units.items():
        for s in series:
            kind = s.name.split("@")[0] if len(series) > MAX_LINES else ""
            groups.setdefault((x_unit, y_unit, kind), []).append(s)
    out = []
    for (x_unit, y_unit, _), series in groups.items():
        if run.assistant == "circle" and x_unit == "°":  # the circle's radial deviation
            axes = str(run.result.inputs.get("axis", "  "))
            lines = [svg.Line(s.name, s.x, s.y) for s in series]
            out.append(
                f'<figure class="plot">{polar.render(lines, axes[:1], axes[1:])}<figcaption>'
                f"radial deviation about the least-squares centre, {y_unit} (run #{run.id})"
                "</figcaption></figure>"
            )
            continue
        # a few figures in the series' own unit are levels worth seeing on it (the mean lag,
        # the lag monitoring limit); many would hide the data
        refs = [
            (f"{f.name} = {number(f.value)} {f.unit}", f.value)
            for f in run.result.figures
            if y_unit and f.unit == y_unit
        ]
        refs = refs if len(refs) <= MAX_LEVELS else []
        x_title = "time" if x_unit == "s" else ""  # else the unit says (a speed: °/s)
        y_title = series[0].name if len(series) == 1 else ""
        lines = [svg.Line(s.name, s.x, s.y) for s in series]
        # a frequency response reads on a logarithmic frequency axis
        log_x = x_unit == "Hz"
        x_title = "frequency" if log_x else x_title
        plot = svg.Plot(lines, x_title, x_unit, y_title, y_unit, refs, log_x=log_x)
        names = ", ".join(s.name for s in series)
        over = f" over {x_title}" if x_title else ""
        stored = sum(len(s.x) for s in series)
        out.append(
            f'<figure class="plot">{svg.render(plot)}<figcaption>{e(names)}{over}'
            f" (run #{run.id}, {stored} stored points)</figcaption></figure>"
        )
    return "".join(out)


InForce = dict[tuple[str, str], object]  # (target, parameter) -> its list value now
SWEEP = re.compile(r"^(.+)@(-?[0-9.]+(?:e-?[0-9]+)?)$")  # a figure of one swept value: name@13.12
MIN_SWEEP = 6  # figures of a sweep before they read as one table


def _figures(run: AssistRun) -> str:
    """The run's figures; those of a sweep (name@value, e.g. lag_overshoot_pct@13.12) as one
    table with a row per swept value and a column per figure, the rest as they are."""
    swept: dict[float, dict[str, float]] = {}
    names: list[str] = []
    single = []
    units: dict[str, str] = {}
    for f in run.result.figures:
        m = SWEEP.match(f.name)
        if m is None:
            single.append(f)
            continue
        name, at = m.group(1), float(m.group(2))
        swept.setdefault(at, {})[name] = f.value
        units[name] = f.unit
        if name not in names:
            names.append(name)
    if sum(len(v) for v in swept.values()) < MIN_SWEEP:  # a few: each in its own row
        single, swept = list(run.result.figures), {}
    rows = [
        f'<tr data-figure="{e(f.name)}"><td><code>{e(f.name)}</code></td>'
        f'<td class="num">{e(number(f.value))}</td><td>{e(f.unit)}</td><td>{e(f.text)}</td></tr>'
        for f in single
    ]
    out = table(["Figure", "Value", "Unit", "Meaning"], rows, "figures") if rows else ""
    if swept:
        head = ["swept value", *(f"{n} [{units[n]}]" if units[n] else n for n in names)]
        body = [
            f'<tr data-sweep="{e(number(at))}"><td class="num">{e(number(at))}</td>'
            + "".join(f'<td class="num">{e(number(swept[at].get(n, "—")))}</td>' for n in names)
            + "</tr>"
            for at in sorted(swept)
        ]
        out += (
            f'<p class="meta">The sweep: {len(swept)} values, {len(names)} figures each.</p>'
            + table(head, body, "figures sweep")
        )
    return out


def _now(before: object, after: object, now: object) -> str:
    """Whether a proposed value is the machine's now."""
    if now == after:
        return '<td class="in-force">in force now</td>'
    if now == before:
        return '<td class="open">not applied</td>'
    return f'<td class="open">now {e(number(now))}</td>'


def _run(run: AssistRun, in_force: InForce) -> str:
    r = run.result
    where = "on the live machine" if run.live else "on a copy of the machine (simulated time)"
    inputs = ", ".join(f"{e(k)} = {e(number(v))}" for k, v in r.inputs.items()) or "—"
    verdict = "" if r.ok else ' <span class="open">(found a fault the changes do not cure)</span>'
    changes = [
        f"<tr><td>{e(c.target)}</td><td><code>{e(c.parameter)}</code></td>"
        f'<td class="num">{e(number(c.before))}</td><td class="num">{e(number(c.after))}</td>'
        + _now(c.before, c.after, in_force.get((c.target, c.parameter), c.before))
        + f"<td>{e(c.why)}</td></tr>"
        for c in r.changes
    ]
    notes = "".join(f"<li>{e(n)}</li>" for n in r.notes)
    head = ["Target", "Parameter", "Before", "Proposed", "On the machine", "Why"]
    return (
        f'<article class="run" id="run-{run.id}" data-run="{run.id}">'
        f"<h3>#{run.id} {e(assistant_title(run.assistant))}"
        f"{' — ' + e(run.axis) if run.axis else ''}{verdict}</h3>"
        f'<p class="meta">Run by <b>{e(run.user)}</b> on {e(when(run.time_unix))}, {where}. '
        f"Inputs: {inputs}.</p>"
        + _figures(run)
        + (
            table(head, changes, "changes")
            if changes
            else '<p class="meta">No parameter change proposed.</p>'
        )
        + _run_plot(run)
        + (f'<ul class="notes">{notes}</ul>' if notes else "")
        + "</article>"
    )


def runs_section(runs: list[AssistRun], left_out: int, in_force: InForce) -> str:
    """Section 1: every run, oldest first; `in_force` the list values of the parameters the
    runs proposed, as they stand now."""
    if not runs:
        body = '<p class="empty">No assistant has run on this machine.</p>'
    else:
        body = "".join(_run(r, in_force) for r in runs)
        if left_out:
            body += f'<p class="meta">{left_out} older runs are not in this report.</p>'
    return f'<section id="runs"><h2>1 Assistant runs</h2>{body}</section>'
