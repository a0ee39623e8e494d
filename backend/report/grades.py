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
class SeatResultRow:
    """One seat's result."""

    n: int
    student: str
    login: str
    joined_unix: float | None
    seat_time_s: float
    checks: tuple[CheckResultRow, ...]
    hints_taken: int
    hint_cost: float
    score: float
    max_points: float

    @property
    def passed(self) -> int:
        return sum(1 for c in self.checks if c.first_passed_s is not None)


@dataclass(frozen=True)
class ClassResults:
    """What the grade list says about a class."""

    id: str
    title: str
    exercise: str
    exercise_title: str
    instructor: str
    created_unix: float
    ended_unix: float | None
    checks: tuple[tuple[str, str], ...]  # (id, text) in the exercise's order
    seats: tuple[SeatResultRow, ...]


def _clock(s: float) -> str:
    t = max(0, int(s))
    return f"{t // 3600}:{t // 60 % 60:02d}:{t % 60:02d}"


def to_csv(r: ClassResults) -> str:
    """One line per seat: who, when they joined, seat time, per check the points earned and
    the seat time of its first pass, hints, score of the maximum."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    head = ["class", "exercise", "seat", "student", "login", "joined_utc", "seat_time_s"]
    for cid, _text in r.checks:
        head += [f"{cid}_points", f"{cid}_first_passed_s"]
    w.writerow([*head, "hints_taken", "hint_cost", "score", "max_points"])
    for s in r.seats:
        joined = (
            time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(s.joined_unix)) if s.joined_unix else ""
        )
        row: list[object] = [r.id, r.exercise, s.n, s.student, s.login, joined]
        row.append(f"{s.seat_time_s:.1f}")
        for c in s.checks:
            row += [
                f"{c.earned:.2f}",
                "" if c.first_passed_s is None else f"{c.first_passed_s:.1f}",
            ]
        w.writerow([*row, s.hints_taken, f"{s.hint_cost:g}", f"{s.score:.2f}", f"{s.max_points:g}"])
    return out.getvalue()


def to_html(r: ClassResults) -> str:
    """The grade list: the class, then a table of the seats (each check's points earned of
    its maximum), the check texts below it, and a line for the instructor's signature."""
    title = f"Results of class {r.title or r.id}"
    ended = f"ended {when(r.ended_unix)}" if r.ended_unix is not None else "still running"
    head = ["Seat", "Student", "Seat time"]
    head += [f"{i + 1}" for i in range(len(r.checks))]
    head += ["Hints", "Score"]
    rows = []
    for s in r.seats:
        cells = [f'<td class="num">{s.n}</td>', f"<td>{e(s.student)}</td>"]
        seat_time = _clock(s.seat_time_s) if s.joined_unix is not None else "not joined"
        if s.joined_unix is None and s.seat_time_s > 0:  # started by the instructor
            seat_time = f"{_clock(s.seat_time_s)} (no login)"
        cells.append(f'<td class="num">{seat_time}</td>')
        for c in s.checks:
            mark = "" if c.first_passed_s is None else " ✓"
            cells.append(f'<td class="num">{c.earned:.1f}/{c.points:g}{mark}</td>')
        cost = f"−{s.hint_cost:g}" if s.hint_cost else "—"
        cells.append(f'<td class="num">{s.hints_taken} ({cost})</td>')
        cells.append(f'<td class="num"><b>{s.score:.1f}</b> of {s.max_points:g}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    legend = "".join(f"<li>{e(text)}</li>" for _cid, text in r.checks)
    footer = f":root {{ --machine: {css_string(title)}; }}"
    return (
        '<!doctype html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{e(title)}</title><style>{CSS.replace('Commissioning report · ', '')}{footer}"
        "</style></head><body><section>"
        f"<h1>{e(title)}</h1>"
        f'<p class="subtitle">{e(r.exercise_title)} <code>{e(r.exercise)}</code></p>'
        f'<p class="meta">Instructor {e(r.instructor)} · began {when(r.created_unix)} · {ended} · '
        f"{len(r.seats)} seats</p>"
        + table(head, rows)
        + f'<h3>Checks</h3><ol class="notes">{legend}</ol>'
        + '<p class="meta">A check earns its points × a time weight of its first pass (1 up to '
        "the par time, falling to 0.5 at three times par); ✓ passed. Hints taken cost their "
        "points. Seat time runs from the student's first login (or the instructor's start).</p>"
        + '<div class="sigs"><div class="sig"><div class="line"></div><span>Instructor, date'
        "</span></div></div></section></body></html>"
    )
