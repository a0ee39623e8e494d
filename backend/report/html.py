"""The commissioning report as one printable HTML document (A4, a page break between
sections, page numbers in the margin), rendered with the standard library: every text from
the store is escaped, every plot is inline SVG drawn from the stored data (backend/report/svg.py).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from api.audit import AuditRecord
from api.report import AssistRun, SignOff
from backend.report import svg
from backend.report.runs import runs_section
from backend.report.text import e, number, table, when

AXIS_KINDS = {"linear": "linear axis", "rotary": "rotary axis", "spindle": "spindle"}


@dataclass(frozen=True)
class MachineFacts:
    id: str
    name: str
    kind: str  # "demo lathe", "from parameter lists"
    axes: list[tuple[str, str]]  # (name, kind)


@dataclass(frozen=True)
class Commissioner:
    """Someone who worked on the machine: assistant runs and parameter changes, first/last."""

    user: str
    runs: int
    changes: int
    first_unix: float
    last_unix: float


@dataclass(frozen=True)
class BaselineRow:
    """A parameter that differs from the baseline: list values in `unit`, and the same in
    engineering units when they differ ('20 → 25 1/s' for a kv in 0.01/s)."""

    target: str
    parameter: str
    id: str  # the manual's, e.g. P-AXIS-00099
    before: object
    after: object
    unit: str
    engineering: str


@dataclass(frozen=True)
class TraceChannel:
    name: str
    unit: str
    values: Sequence[float]


@dataclass(frozen=True)
class TracePlot:
    """A stored trace's channels and what identifies it."""

    id: str
    name: str
    notes: str
    created_unix: float
    trigger: str
    t_s: Sequence[float]
    channels: list[TraceChannel]


@dataclass(frozen=True)
class ReportData:
    machine: MachineFacts
    generated_unix: float
    generated_by: str
    commissioners: list[Commissioner]
    runs: list[AssistRun]  # oldest first
    runs_left_out: int  # older runs beyond the report's bound
    baseline: list[BaselineRow] | None  # None: no baseline set
    traces: list[TracePlot]
    audit: list[AuditRecord]  # newest first
    audit_total: int  # matching rows in all
    audit_commands: int  # command rows left out (in the Audit workspace and audit.csv)
    sign_offs: list[SignOff]
    # the list values now of the parameters the runs proposed: (target, parameter) -> value
    in_force: dict[tuple[str, str], object]


def css_string(text: str) -> str:
    """`text` as a CSS string literal that cannot end the string or the <style> element."""
    safe = (c if c.isalnum() or c in " _.-()" else f"\\{ord(c):x} " for c in text)
    return '"' + "".join(safe) + '"'


def _cover(d: ReportData) -> str:
    m = d.machine
    axes = ", ".join(f"{n} ({AXIS_KINDS.get(k, k)})" for n, k in m.axes) or "none"
    if d.commissioners:
        first = min(c.first_unix for c in d.commissioners)
        last = max(c.last_unix for c in d.commissioners)
        who = "".join(
            f"<li><b>{e(c.user)}</b>: {c.runs} assistant run{'s' * (c.runs != 1)}, "
            f"{c.changes} parameter change{'s' * (c.changes != 1)} "
            f"({e(when(c.first_unix))} – {e(when(c.last_unix))})</li>"
            for c in d.commissioners
        )
        span = f"from {e(when(first))} to {e(when(last))}" if len(d.commissioners) > 1 else ""
        commissioned = f'<ul class="who">{who}</ul>{span}'
    else:
        commissioned = "nobody yet (no assistant run, no parameter change recorded)"
    if d.sign_offs:
        s = d.sign_offs[-1]
        signed = f"<b>{e(s.name)}</b>{', ' + e(s.role) if s.role else ''} on {e(when(s.time_unix))}"
    else:
        signed = '<span class="open">not signed off</span>'
    rows = [
        ("Machine", f"<b>{e(m.name)}</b>"),
        ("Machine id", f"<code>{e(m.id)}</code>"),
        ("Kind", e(m.kind)),
        ("Axes and spindles", e(axes)),
        ("Commissioned by", commissioned),
        ("Signed off", signed),
        ("Report generated", f"{e(when(d.generated_unix))} by {e(d.generated_by)}"),
    ]
    body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    contents = "".join(
        f"<li>{t}</li>"
        for t in (
            f"Assistant runs ({len(d.runs)})",
            "Parameter differences against the baseline",
            f"Traces ({len(d.traces)})",
            "Audit excerpt",
            "Sign-off",
        )
    )
    return (
        '<section class="cover" id="machine"><h1>Commissioning report</h1>'
        f'<p class="subtitle">{e(m.name)}</p>'
        f'<table class="facts">{body}</table>'
        f'<h2 class="small">Contents</h2><ol class="contents">{contents}</ol></section>'
    )


PLANT = "sim."  # the simulated plant's parameters: not the NC's, not commissioning


def _diff_table(rows: list[BaselineRow]) -> str:
    body = [
        f'<tr data-parameter="{e(b.target)}.{e(b.parameter)}"><td>{e(b.target)}</td>'
        f'<td><code>{e(b.parameter)}</code><div class="id">{e(b.id)}</div></td>'
        f'<td class="num">{e(number(b.before))}</td>'
        f'<td class="num">{e(number(b.after))}</td><td>{e(b.unit)}</td>'
        f"<td>{e(b.engineering)}</td></tr>"
        for b in rows
    ]
    head = ["Target", "Parameter", "Baseline", "Now", "Unit", "Engineering"]
    return table(head, body, "diff")


def _baseline(d: ReportData) -> str:
    """The NC's parameters that differ from the baseline; the simulated plant's (sim.*: a
    training fault's drive gain, a softer coupling) apart, as no commissioning change."""
    if d.baseline is None:
        body = (
            '<p class="empty" data-testid="no-baseline">No baseline set: set one at the start '
            "of commissioning to see what changed since.</p>"
        )
    else:
        nc = [b for b in d.baseline if not b.parameter.startswith(PLANT)]
        plant = [b for b in d.baseline if b.parameter.startswith(PLANT)]
        if not nc:
            body = '<p class="empty">No parameter of the NC differs from the baseline.</p>'
        else:
            body = (
                f'<p class="meta">{len(nc)} parameters differ from the baseline '
                "(list values; a value not written counts as the manual's default).</p>"
                + _diff_table(nc)
            )
        if plant:
            body += (
                f'<h3 id="plant-changes">The simulated plant ({len(plant)} changed)</h3>'
                '<p class="meta">Not the NC\'s parameters and no commissioning change: the '
                "simulated motor, drive and mechanics (sim.*) as someone set them.</p>"
                + _diff_table(plant)
            )
    title = "2 Parameter differences against the baseline"
    return f'<section id="baseline"><h2>{title}</h2>{body}</section>'


_UNIT_END = re.compile(r"_(mm_min|mm_s2|deg_s2|mm|deg|rpm|pct|um|nm|s)$")
_ROLE = re.compile(r"_(cmd|act|true)(?=_|$)")


def quantity(name: str) -> str:
    """What a channel measures, from its name, as the HMI's charts group it
    (frontend/src/ui/scopeAxes.ts): X.pos_act_mm and X.pos_cmd_mm → "pos", S1.lag_deg → "lag"."""
    stem = name.rsplit(".", 1)[-1]
    return _ROLE.sub("", _UNIT_END.sub("", stem), count=1) or stem


def _traces(d: ReportData) -> str:
    """Each chosen trace: every channel, one plot per quantity (a spindle's 600 000° position
    would flatten its lag, a speed its lag; commanded and actual of one quantity share)."""
    if not d.traces:
        body = '<p class="empty">No trace chosen for this report.</p>'
    else:
        parts = []
        for t in d.traces:
            by_unit: dict[tuple[str, str], list[TraceChannel]] = {}
            for c in t.channels:
                by_unit.setdefault((quantity(c.name), c.unit), []).append(c)
            figures = "".join(
                '<figure class="plot">'
                + svg.render(
                    svg.Plot(
                        [svg.Line(c.name, t.t_s, c.values) for c in group],
                        "time from the trigger",
                        "s",
                        group[0].name if len(group) == 1 else what,
                        unit,
                    )
                )
                + f"<figcaption>{e(', '.join(c.name for c in group))}</figcaption></figure>"
                for (what, unit), group in by_unit.items()
            )
            notes = f'<p class="meta">{e(t.notes)}</p>' if t.notes else ""
            names = ", ".join(c.name for c in t.channels)
            parts.append(
                f'<article class="trace" data-trace="{e(t.id)}"><h3>{e(t.name or t.id)}</h3>'
                f'<p class="meta">Captured {e(when(t.created_unix))}, trigger: {e(t.trigger)}, '
                f"{len(t.t_s)} samples; channels: {e(names)}.</p>{notes}{figures}</article>"
            )
        body = "".join(parts)
    return f'<section id="traces"><h2>3 Traces</h2>{body}</section>'


def _audit(d: ReportData) -> str:
    rows = [
        f'<tr class="{"refused" if a.outcome != "ok" else ""}">'
        f'<td class="time">{e(when(a.time_unix))}</td>'
        f"<td>{e(a.actor)}</td><td>{e(a.kind)}</td><td>{e(a.action)}</td>"
        f"<td>{e(a.outcome)}</td></tr>"
        for a in d.audit
    ]
    shown = (
        f"The newest {len(d.audit)} of {d.audit_total} entries"
        if len(d.audit) < d.audit_total
        else f"All {d.audit_total} entries"
    )
    left = (
        f"; {d.audit_commands} NC commands (jog, MDI, …) are left out" if d.audit_commands else ""
    )
    body = (
        f'<p class="meta">{shown} of this machine, newest first{left}. The whole trail: '
        f"the Audit workspace or <code>GET /api/machines/{e(d.machine.id)}/audit.csv</code>.</p>"
        + (table(["Time", "User", "Kind", "Action", "Outcome"], rows, "audit") if rows else "")
    )
    return f'<section id="audit"><h2>4 Audit excerpt</h2>{body}</section>'


def _sign_off(d: ReportData) -> str:
    if d.sign_offs:
        rows = [
            f'<tr data-sign-off="{s.id}"><td><b>{e(s.name)}</b></td><td>{e(s.role)}</td>'
            f"<td>{e(s.remark)}</td><td>{e(when(s.time_unix))}</td><td>{e(s.user)}</td></tr>"
            for s in d.sign_offs
        ]
        body = table(["Name", "Function", "Remark", "Signed", "Recorded by"], rows, "signoff")
    else:
        body = '<p class="empty">Not signed off yet.</p>'
    lines = "".join(
        f'<div class="sig"><div class="line"></div><span>{t}</span></div>'
        for t in ("Place, date", "Commissioning engineer", "Customer")
    )
    return (
        f'<section id="sign-off"><h2>5 Sign-off</h2>{body}'
        '<p class="meta">Signatures on the printed copy:</p>'
        f'<div class="sigs">{lines}</div></section>'
    )


CSS = """
@page { size: A4; margin: 16mm 15mm 18mm 15mm;
  @bottom-left { content: "Commissioning report · " var(--machine);
    font: 8pt sans-serif; color: #555; }
  @bottom-right { content: "page " counter(page) " of " counter(pages);
    font: 8pt sans-serif; color: #555; } }
* { box-sizing: border-box; }
html { background: #e5e7eb; }
body { font: 10pt/1.4 "DejaVu Sans", "Liberation Sans", Arial, sans-serif; color: #111;
  margin: 0 auto; padding: 12mm 15mm; max-width: 210mm; background: #fff; }
h1 { font-size: 22pt; margin: 0 0 2mm; }
h2 { font-size: 14pt; border-bottom: 1.5pt solid #1f5fa8; padding-bottom: 1mm; margin: 0 0 4mm; }
h2.small { font-size: 11pt; margin-top: 8mm; }
h3 { font-size: 11pt; margin: 5mm 0 1mm; }
.subtitle { font-size: 14pt; color: #1f5fa8; margin: 0 0 8mm; }
section + section { break-before: page; margin-top: 12mm; }
article { break-inside: avoid; padding-top: 1mm; }
article + article { border-top: 0.5pt solid #ccc; margin-top: 4mm; }
table { border-collapse: collapse; width: 100%; margin: 2mm 0 3mm; font-size: 9pt; }
th, td { text-align: left; vertical-align: top; padding: 1mm 2mm; border-bottom: 0.5pt solid #ddd; }
thead th { background: #f1f5f9; border-bottom: 1pt solid #999; }
table.facts th { width: 42mm; background: none; color: #444; font-weight: normal; }
table.facts td, table.facts th { font-size: 10pt; padding: 1.5mm 2mm; }
td.time { white-space: nowrap; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
div.id { font-size: 8pt; color: #555; }
code { font: 8.5pt "DejaVu Sans Mono", monospace; }
tr.refused td { color: #9a3412; }
ul.who { margin: 0 0 1mm; padding-left: 5mm; }
.meta { color: #333; margin: 1mm 0; }
.empty { color: #555; font-style: italic; }
.open { color: #9a3412; font-weight: bold; }
.in-force { color: #0d5a26; font-weight: bold; }
ul.notes { margin: 1mm 0 2mm; padding-left: 5mm; color: #333; }
figure.plot { margin: 2mm 0; }
figure.plot svg { width: 100%; height: auto; max-width: 170mm; display: block; }
figcaption { font-size: 8.5pt; color: #555; }
svg.plot text { font: 11px "DejaVu Sans", Arial, sans-serif; fill: #222; }
.sigs { display: flex; gap: 8mm; margin-top: 18mm; }
.sig { flex: 1; }
.sig .line { border-bottom: 0.75pt solid #111; height: 12mm; }
.sig span { font-size: 8.5pt; color: #444; }
@media print { html { background: none; } body { padding: 0; max-width: none; }
  section + section { margin-top: 0; } }
"""


def render(d: ReportData) -> str:
    """The whole report as one HTML document."""
    title = f"Commissioning report {d.machine.name} ({d.machine.id})"
    machine_css = f":root {{ --machine: {css_string(d.machine.name)}; }}"
    return (
        '<!doctype html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{e(title)}</title>"
        f"<style>{CSS}{machine_css}</style></head><body>"
        + _cover(d)
        + runs_section(d.runs, d.runs_left_out, d.in_force)
        + _baseline(d)
        + _traces(d)
        + _audit(d)
        + _sign_off(d)
        + "</body></html>"
    )
