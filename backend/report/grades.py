"""A class's results: one row per seat with what each check earned, as CSV (for a
spreadsheet or a learning platform) and as a printable grade list (A4 HTML, printed to PDF
as the commissioning report is). The numbers are the scores the console shows: a check's
points × the time weight of its first pass, minus the hints taken (nc_sim/training/score.py).
"""

from __future__ import annotations

import csv
import io
import time
from dataclasses import dataclass

from backend.report.html import CSS, css_string
from backend.report.text import e, table, when


@dataclass(frozen=True)
class CheckResultRow:
    """One check of one seat: its points, what it earned, when it first passed."""

    id: str
    points: float
    earned: float
    first_passed_s: float | None


@dataclass(frozen=True)
class StageRow:
    """One seat in one exercise of the lesson plan."""

    exercise: str
    seat_time_s: float
    finished_s: float | None  # its clock when every check had passed
    checks: tuple[CheckResultRow, ...]
    hints_taken: int
    hint_cost: float
    score: float

    @property
    def passed(self) -> int:
        return sum(1 for c in self.checks if c.first_passed_s is not None)


@dataclass(frozen=True)
class SeatResultRow:
    """One seat's result: a row per exercise of the plan it reached."""

    n: int
    student: str
    login: str
    joined_unix: float | None
    stages: tuple[StageRow, ...]

    def stage(self, exercise: str) -> StageRow | None:
        return next((r for r in self.stages if r.exercise == exercise), None)

    @property
    def score(self) -> float:
        return sum(r.score for r in self.stages)

    @property
    def seat_time_s(self) -> float:
        return sum(r.seat_time_s for r in self.stages)


@dataclass(frozen=True)
class ExerciseColumns:
    """One exercise of the plan: its checks (id, text) in order and its maximum."""

    id: str
    title: str
    max_points: float
    checks: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class ClassResults:
    """What the grade list says about a class."""

    id: str
    title: str
    instructor: str
    created_unix: float
    ended_unix: float | None
    exercises: tuple[ExerciseColumns, ...]  # the lesson plan
    seats: tuple[SeatResultRow, ...]

    @property
    def max_points(self) -> float:
        return sum(x.max_points for x in self.exercises)


def _clock(s: float) -> str:
    t = max(0, int(s))
    return f"{t // 3600}:{t // 60 % 60:02d}:{t % 60:02d}"


def _utc(t: float | None) -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t)) if t else ""


def to_csv(r: ClassResults) -> str:
    """One line per seat and exercise of the plan (`reached` no: 0 of its maximum, so a
    student's lines add up to the plan's maximum): who, when they joined, the exercise's seat
    time and when every check had passed, per check (`<exercise>.<check>`) the points earned
    and the seat time of its first pass (empty for another exercise's checks), hints, score
    of the maximum."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    head = ["class", "exercise", "reached", "seat", "student", "login", "joined_utc"]
    head += ["seat_time_s", "finished_s"]
    for x in r.exercises:
        for cid, _text in x.checks:
            head += [f"{x.id}.{cid}_points", f"{x.id}.{cid}_first_passed_s"]
    w.writerow([*head, "checks_passed", "hints_taken", "hint_cost", "score", "max_points"])
    for s in r.seats:
        for x in r.exercises:
            st = s.stage(x.id)
            who = [s.n, s.student, s.login, _utc(s.joined_unix)]
            if st is None:  # not reached: nothing earned of its maximum
                blank = [""] * sum(2 * len(o.checks) for o in r.exercises)
                w.writerow(
                    [r.id, x.id, "no", *who, "", "", *blank, 0, 0, 0, "0.00", f"{x.max_points:g}"]
                )
                continue
            row: list[object] = [r.id, x.id, "yes", *who, f"{st.seat_time_s:.1f}"]
            row.append("" if st.finished_s is None else f"{st.finished_s:.1f}")
            for other in r.exercises:
                if other is not x:
                    row += [""] * (2 * len(other.checks))
                    continue
                for c in st.checks:
                    passed = "" if c.first_passed_s is None else f"{c.first_passed_s:.1f}"
                    row += [f"{c.earned:.2f}", passed]
            row += [st.passed, st.hints_taken, f"{st.hint_cost:g}", f"{st.score:.2f}"]
            w.writerow([*row, f"{x.max_points:g}"])
    return out.getvalue()


def _exercise_table(r: ClassResults, k: int, x: ExerciseColumns) -> str:
    """One exercise of the plan: a row per seat (each check's points earned of its maximum),
    its checks' texts below."""
    head = ["Seat", "Student", "Seat time"]
    head += [f"{i + 1}" for i in range(len(x.checks))]
    head += ["Hints", "Score"]
    rows = []
    for s in r.seats:
        cells = [f'<td class="num">{s.n}</td>', f"<td>{e(s.student)}</td>"]
        st = s.stage(x.id)
        if st is None:
            span = len(x.checks) + 3
            rows.append("<tr>" + "".join(cells) + f'<td colspan="{span}">not reached</td></tr>')
            continue
        seat_time = _clock(st.seat_time_s) if s.joined_unix is not None else "not joined"
        if s.joined_unix is None and st.seat_time_s > 0:  # started by the instructor
            seat_time = f"{_clock(st.seat_time_s)} (no login)"
        if st.finished_s is not None:
            seat_time = f"done in {_clock(st.finished_s)}"
        cells.append(f'<td class="num">{seat_time}</td>')
        for c in st.checks:
            mark = "" if c.first_passed_s is None else " ✓"
            cells.append(f'<td class="num">{c.earned:.1f}/{c.points:g}{mark}</td>')
        cost = f"−{st.hint_cost:g}" if st.hint_cost else "—"
        cells.append(f'<td class="num">{st.hints_taken} ({cost})</td>')
        cells.append(f'<td class="num"><b>{st.score:.1f}</b> of {x.max_points:g}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    legend = "".join(f"<li>{e(text)}</li>" for _cid, text in x.checks)
    which = f"Exercise {k + 1}: " if len(r.exercises) > 1 else ""
    return (
        f"<h3>{which}{e(x.title)} <code>{e(x.id)}</code></h3>"
        + table(head, rows)
        + f'<ol class="notes">{legend}</ol>'
    )


def _totals(r: ClassResults) -> str:
    """Each seat's score per exercise and over the plan."""
    head = ["Seat", "Student", *[f"{k + 1}" for k in range(len(r.exercises))], "Total"]
    rows = []
    for s in r.seats:
        cells = [f'<td class="num">{s.n}</td>', f"<td>{e(s.student)}</td>"]
        for x in r.exercises:
            st = s.stage(x.id)
            cells.append(f'<td class="num">{"—" if st is None else f"{st.score:.1f}"}</td>')
        cells.append(f'<td class="num"><b>{s.score:.1f}</b> of {r.max_points:g}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return "<h3>Over the lesson plan</h3>" + table(head, rows)


def to_html(r: ClassResults) -> str:
    """The grade list: the class, a table per exercise of the lesson plan (each check's
    points earned of its maximum, the check texts below), the totals over the plan, and a
    line for the instructor's signature."""
    title = f"Results of class {r.title or r.id}"
    ended = f"ended {when(r.ended_unix)}" if r.ended_unix is not None else "still running"
    plan = " → ".join(x.title for x in r.exercises)
    body = "".join(_exercise_table(r, k, x) for k, x in enumerate(r.exercises))
    if len(r.exercises) > 1:
        body += _totals(r)
    footer = f":root {{ --machine: {css_string(title)}; }}"
    return (
        '<!doctype html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{e(title)}</title><style>{CSS.replace('Commissioning report · ', '')}{footer}"
        "</style></head><body><section>"
        f"<h1>{e(title)}</h1>"
        f'<p class="subtitle">{e(plan)}</p>'
        f'<p class="meta">Instructor {e(r.instructor)} · began {when(r.created_unix)} · {ended} · '
        f"{len(r.seats)} seats</p>"
        + body
        + '<p class="meta">A check earns its points × a time weight of its first pass (1 up to '
        "the par time, falling to 0.5 at three times par); ✓ passed. Hints taken cost their "
        "points. Seat time runs from the student's first login (or the instructor's start); "
        "each exercise has its own clock.</p>"
        + '<div class="sigs"><div class="sig"><div class="line"></div><span>Instructor, date'
        "</span></div></div></section></body></html>"
    )
