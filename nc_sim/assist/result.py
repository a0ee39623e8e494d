"""What an assistant answers: figures, proposed parameter changes, plot series."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

Value = float | int | str


class ExperimentError(ValueError):
    """The assistant cannot run as asked (bad inputs, unknown axis, no speed, refused
    motion)."""


@dataclass(frozen=True)
class Figure:
    """One measured or computed figure, in the unit the manual gives it in."""

    name: str  # e.g. "k" (effective gain), "lag_mm"
    value: float
    unit: str  # "1/s", "mm", "" for a ratio
    text: str = ""  # what it is, in the engineer's words


@dataclass(frozen=True)
class Change:
    """A parameter change an assistant proposes: `target` is the axis name (X, S1) or
    "channel", `parameter` the list name (getriebe[0].multi_gain_z) in raw list units."""

    target: str
    parameter: str
    before: Value
    after: Value
    why: str = ""


@dataclass(frozen=True)
class Series:
    """A plot's data: y over x (same length), with names and units."""

    name: str
    x: tuple[float, ...]
    y: tuple[float, ...]
    x_unit: str = ""
    y_unit: str = ""


@dataclass(frozen=True)
class Result:
    """An assistant's answer. `notes` say what the engineer should know (a warning that the
    loop gain rises, a check from the manual); `ok` is false when the run found a fault that
    the changes do not cure (then `notes` say why)."""

    assistant: str
    figures: tuple[Figure, ...] = ()
    changes: tuple[Change, ...] = ()
    series: tuple[Series, ...] = ()
    notes: tuple[str, ...] = ()
    ok: bool = True
    inputs: dict[str, Value] = field(default_factory=dict)

    def figure(self, name: str) -> float:
        """The value of figure `name` (KeyError without one)."""
        for f in self.figures:
            if f.name == name:
                return f.value
        raise KeyError(name)

    def as_json(self) -> dict[str, Any]:
        """Plain JSON values (the command line's --json, the service's answer)."""
        return {
            "assistant": self.assistant,
            "ok": self.ok,
            "inputs": dict(self.inputs),
            "figures": [vars(f) for f in self.figures],
            "changes": [vars(c) for c in self.changes],
            "series": [{**vars(s), "x": list(s.x), "y": list(s.y)} for s in self.series],
            "notes": list(self.notes),
        }
