"""What describes a commissioning assistant (nc_sim/assist/registry.py holds them all): its
name, title, manual section, typed inputs with ranges and units, the figures that say what it
found, where it runs and its procedure, named as "module:function" and imported only when it
runs (this module loads no kernel: the gateway and the API models read it).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Literal


class Kind(StrEnum):
    """A calculator answers at once from its inputs (arithmetic, no machine moves); an
    experiment drives a copy of the machine in simulated time (and, if `live`, the machine
    itself)."""

    CALCULATOR = "calculator"
    EXPERIMENT = "experiment"


class Required:
    """The default of an input the caller must give."""


REQUIRED = Required()


@dataclass(frozen=True)
class Number:
    """A number within [lo, hi] (lo excluded with `lo_open`), in `unit`; `optional`: may be
    null (the procedure then takes its own default)."""

    name: str
    text: str
    unit: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    default: float | int | Required | None = REQUIRED
    integer: bool = False
    optional: bool = False
    cli: str = ""  # the command line's option when not the name's (--feed for feed_mm_min)

    def check(self, value: object) -> str:
        """Why `value` is refused ("" when it is not)."""
        if value is None:
            return "" if self.optional else f"{self.name}: a value is needed"
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"{self.name}: a number is needed"
        if not math.isfinite(value):
            return f"{self.name}: a finite number is needed"
        if self.integer and not float(value).is_integer():
            return f"{self.name}: a whole number is needed"
        low = self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo)
        if low or (self.hi is not None and value > self.hi):
            return f"{self.name}: {value:g} is out of range ({self.range_text()})"
        return ""

    def range_text(self) -> str:
        """'> 0 and ≤ 100 mm': the range in words, with the unit."""
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '≥'} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"≤ {self.hi:g}")
        return " and ".join(parts) + (f" {self.unit}" if self.unit else "")


@dataclass(frozen=True)
class Choice:
    """One of a few integer options, each with what it means."""

    name: str
    text: str
    options: tuple[tuple[int, str], ...]
    default: int | Required | None = REQUIRED
    optional: bool = False
    cli: str = ""

    def check(self, value: object) -> str:
        if value is None and self.optional:
            return ""
        if value not in [o for o, _ in self.options]:
            allowed = ", ".join(f"{o} ({t})" for o, t in self.options)
            return f"{self.name}: must be one of {allowed}"
        return ""


@dataclass(frozen=True)
class Flag:
    """Yes or no."""

    name: str
    text: str
    default: bool = False
    cli: str = ""
    optional: bool = False

    def check(self, value: object) -> str:
        return "" if isinstance(value, bool) else f"{self.name}: true or false"


AxisKind = Literal["linear", "rotary", "spindle"]


@dataclass(frozen=True)
class AxisChoice:
    """The axis (or spindle) the assistant works on, of one of `kinds`."""

    name: str = "axis"
    text: str = "axis or spindle name"
    kinds: tuple[AxisKind, ...] = ("linear", "rotary", "spindle")
    cli: str = ""
    default: Required = REQUIRED
    optional: bool = False

    def check(self, value: object) -> str:
        ok = isinstance(value, str) and 1 <= len(value) <= 16
        return "" if ok else f"{self.name}: an axis name (1-16 characters)"


@dataclass(frozen=True)
class NumberList:
    """Several numbers of the same kind (`item`), e.g. the kv values of a sweep."""

    name: str
    text: str
    item: Number
    min_len: int = 1
    max_len: int = 12
    optional: bool = False
    default: Required | None = REQUIRED
    cli: str = ""

    def check(self, value: object) -> str:
        if value is None and self.optional:
            return ""
        if not isinstance(value, list) or not self.min_len <= len(value) <= self.max_len:
            return f"{self.name}: {self.min_len} to {self.max_len} numbers"
        return next((e for e in (self.item.check(v) for v in value) if e), "")


@dataclass(frozen=True)
class Table:
    """Rows of numbers (`columns`), e.g. the points (n, a) of a curve; `row` names a row's
    model in the API."""

    name: str
    text: str
    row: str
    columns: tuple[Number, ...]
    min_len: int = 1
    max_len: int = 500
    default: Required = REQUIRED
    optional: bool = False
    cli: str = ""

    def check(self, value: object) -> str:
        if not isinstance(value, list) or not self.min_len <= len(value) <= self.max_len:
            given = f" ({len(value)} given)" if isinstance(value, list) else ""
            return f"{self.name}: {self.min_len} to {self.max_len} rows{given}"
        for row in value:
            if not isinstance(row, dict):
                return f"{self.name}: each row has {', '.join(c.name for c in self.columns)}"
            why = next((e for e in (c.check(row.get(c.name)) for c in self.columns) if e), "")
            if why:
                return f"{self.name}: {why}"
        return ""


Input = Number | Choice | Flag | AxisChoice | NumberList | Table


@dataclass(frozen=True)
class Assistant:
    """One assistant. `run` is "module:function" taking the machine's configuration and the
    inputs as keywords and answering a `Result` (on a copy; a calculator: at once; empty for
    an experiment whose `live` procedure runs on a fresh copy as it is); `live`,
    when it may run on the machine itself, takes the machine and the inputs and is a
    `Procedure` its worker paces. `request` names the API's model of its inputs; `summary`
    the figures that say what a run found (the run list, the report)."""

    name: str
    title: str
    section: str
    text: str
    kind: Kind
    request: str
    inputs: tuple[Input, ...]
    run: str
    summary: tuple[str, ...] = ()
    live: str = ""

    def input(self, name: str) -> Input:
        return next(i for i in self.inputs if i.name == name)

    def check(self, values: Mapping[str, object]) -> list[str]:
        """Why the inputs are refused, one sentence per input (none when they are fine)."""
        unknown = [k for k in values if k not in {i.name for i in self.inputs}]
        errors = [f"{k}: not an input of {self.name}" for k in unknown]
        for i in self.inputs:
            if i.name not in values and isinstance(i.default, Required):
                errors.append(f"{i.name}: a value is needed")
            elif i.name in values and (why := i.check(values[i.name])):
                errors.append(why)
        return errors

    def with_defaults(self, values: Mapping[str, object]) -> dict[str, object]:
        """The inputs as given, the defaults for the rest."""
        out = {i.name: i.default for i in self.inputs if not isinstance(i.default, Required)}
        return out | dict(values)


def resolve(ref: str) -> Callable[..., Any]:
    """The function "module:function" names (imported now)."""
    module, _, func = ref.partition(":")
    fn: Callable[..., Any] = getattr(importlib.import_module(module), func)
    return fn
