"""The exercise file format (TOML), parsed and validated in full before anything runs.

    id = "sign-error"                 # [a-z0-9-], the file's name without .toml
    title = "..."
    summary = "..."                   # one or two sentences for the list of exercises
    task = \"\"\"...\"\"\"                  # the task text the student reads (plain text)
    par_time_s = 900                  # the time a good student needs
    machine = "demo"                  # the machine template

    [[start]]                         # starting parameter values, written before it starts
    scope = "axis"                    # channel | axis | tool
    target = "S1"                     # the axis (axis scope only)
    name = "sim.drive_a_max"
    value = 2000                      # in the list's unit, as a list file writes it

    [[faults]]                        # kind and fields as in nc_sim/faults.py
    kind = "motor_inverted"
    axis = "X"
    trigger = { after_s = 0, on_motion = false }   # optional: at once

    [[hints]]
    text = "..."
    cost = 10                         # points off the score when taken

    [[checks]]                        # kind and its fields as in nc_sim/training/checks.py
    id = "gain"
    text = "..."                      # what the student sees
    points = 60
    kind = "gain"
    axis = "X"
    within_pct = 1.0

    locked_assistants = ["multi-gain"]   # optional: assistants the student may not use

    [[vary]]                          # optional: numbers drawn per seat (variation.py)
    key = "faults[0].factor"
    min = 0.35
    max = 0.6
    step = 0.005

Every error is an `ExerciseError` naming the file, the key path (`checks[2].axis`), the value
and what is allowed; a TOML syntax error keeps tomllib's line and column. Axis names are
checked only for their form here: the machine is not known until a seat starts.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from nc_sim.assist.registry import ASSISTANTS
from nc_sim.errors import Code
from nc_sim.faults import CATALOGUE, NOW, Fault, Trigger
from nc_sim.params import ParamError, Scope, Value, resolve
from nc_sim.plant.tuning import TEMPLATES
from nc_sim.training.checks import RULES, Check, FindingCheck, Rule
from nc_sim.training.findings import FINDABLE
from nc_sim.training.variation import KEY_RE, MAX_STEPS, Vary, draw

MACHINES = ("demo",)  # machine templates a seat can start from
MAX_FILE_CHARS = 200_000
MAX_ITEMS = 32  # starting values, faults, hints, checks: each at most this many
MAX_TITLE = 120
MAX_SUMMARY = 600
MAX_TASK = 20_000
MAX_TEXT = 2_000  # a hint's or a check's text
MAX_POINTS = 1000.0
MAX_PAR_TIME_S = 86_400.0
MAX_WINDOW_S = 3_600.0
ID_RE = re.compile(r"[a-z0-9][a-z0-9-]{0,63}")
AXIS_RE = re.compile(r"[A-Z][A-Z0-9]{0,15}")


class ExerciseError(ValueError):
    """A bad exercise file: which file, which key, which value, what is allowed."""

    def __init__(self, source: str, key: str, value: object, allowed: str) -> None:
        self.source = source
        self.key = key
        self.value = value
        self.allowed = allowed
        where = f"{source}: {key} = {value!r}" if key else source
        super().__init__(f"{where}: {allowed}")


@dataclass(frozen=True)
class StartValue:
    """A parameter value written into the seat's lists before the machine starts."""

    scope: Scope
    target: str  # the axis for axis scope, "" else
    name: str
    value: Value


@dataclass(frozen=True)
class FaultSpec:
    """A fault injected when the seat starts, and when it takes effect."""

    fault: Fault
    trigger: Trigger = NOW


@dataclass(frozen=True)
class Hint:
    text: str
    cost: float  # points off the score when taken


@dataclass(frozen=True)
class Exercise:
    """One exercise as its file describes it."""

    id: str
    title: str
    summary: str
    task: str
    par_time_s: float
    machine: str
    start: tuple[StartValue, ...]
    faults: tuple[FaultSpec, ...]
    hints: tuple[Hint, ...]
    checks: tuple[Check, ...]
    locked: tuple[str, ...] = ()  # assistants the student may not use
    vary: tuple[Vary, ...] = ()  # numbers drawn per seat

    def with_values(self, values: Mapping[str, float]) -> Exercise:
        """The exercise with its varied numbers set (key -> value; those not named keep the
        file's)."""
        faults, start = list(self.faults), list(self.start)
        for v in self.vary:
            if v.key not in values:
                continue
            x = values[v.key]
            if v.section == "faults":
                f = faults[v.index]
                changed = dataclasses.replace(typing.cast(Any, f.fault), **{v.field: x})
                faults[v.index] = FaultSpec(changed, f.trigger)
            else:
                start[v.index] = dataclasses.replace(start[v.index], value=x)
        return dataclasses.replace(self, faults=tuple(faults), start=tuple(start))

    def for_seat(self, seed: int, seat: int) -> tuple[Exercise, dict[str, float]]:
        """Seat `seat`'s exercise: its numbers drawn from the class's `seed`
        (variation.seat_seed), and them."""
        values = draw(self.vary, seed, seat)
        return self.with_values(values), values

    def extremes(self) -> tuple[Exercise, Exercise]:
        """The exercise with every varied number at its minimum, and at its maximum (what a
        machine must take: both are checked against it)."""
        return (
            self.with_values({v.key: v.lo for v in self.vary}),
            self.with_values({v.key: v.hi for v in self.vary}),
        )

    @property
    def max_points(self) -> float:
        """The score of a student who passes every check in par time and takes no hint."""
        return sum(c.points for c in self.checks)


class _Reader:
    """Typed access to one table of the file, with the key path for errors."""

    def __init__(self, source: str, table: Mapping[str, Any], path: str) -> None:
        self.source = source
        self.table = table
        self.path = path

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def fail(self, name: str, value: object, allowed: str) -> ExerciseError:
        return ExerciseError(self.source, self.key(name), value, allowed)

    def only(self, allowed: typing.Iterable[str]) -> None:
        known = set(allowed)
        for name, value in self.table.items():
            if name not in known:
                raise self.fail(name, value, f"unknown key (allowed: {', '.join(sorted(known))})")

    def has(self, name: str) -> bool:
        return name in self.table

    def raw(self, name: str) -> Any:
        if name not in self.table:
            raise self.fail(name, None, "missing")
        return self.table[name]

    def text(self, name: str, max_len: int, pattern: re.Pattern[str] | None = None) -> str:
        v = self.raw(name)
        if not isinstance(v, str) or not v.strip():
            raise self.fail(name, v, "a non-empty string")
        if len(v) > max_len:
            raise self.fail(name, v[:40] + "…", f"at most {max_len} characters, not {len(v)}")
        if pattern is not None and not pattern.fullmatch(v):
            raise self.fail(name, v, f"must match {pattern.pattern}")
        return v

    def number(self, name: str, lo: float, hi: float, lo_open: bool = False) -> float:
        v = self.raw(name)
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.fail(name, v, "a number")
        ok = (v > lo if lo_open else v >= lo) and v <= hi
        if not ok:
            low = f"> {lo:g}" if lo_open else f"≥ {lo:g}"
            raise self.fail(name, v, f"a number {low} and ≤ {hi:g}")
        return float(v)

    def integer(self, name: str, lo: int, hi: int) -> int:
        v = self.raw(name)
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise self.fail(name, v, f"a whole number {lo}..{hi}")
        return v

    def flag(self, name: str) -> bool:
        v = self.raw(name)
        if not isinstance(v, bool):
            raise self.fail(name, v, "true or false")
        return v

    def axis(self, name: str) -> str:
        return self.text(name, 16, AXIS_RE)

    def items(self, name: str) -> list[_Reader]:
        """An array of tables (`[[name]]`), at most MAX_ITEMS; empty when absent."""
        v = self.table.get(name, [])
        if not isinstance(v, list) or not all(isinstance(t, dict) for t in v):
            raise self.fail(name, v, "an array of tables ([[" + name + "]])")
        if len(v) > MAX_ITEMS:
            raise self.fail(name, f"{len(v)} entries", f"at most {MAX_ITEMS}")
        return [_Reader(self.source, t, f"{self.key(name)}[{i}]") for i, t in enumerate(v)]

    def sub(self, name: str) -> _Reader:
        v = self.raw(name)
        if not isinstance(v, dict):
            raise self.fail(name, v, "a table")
        return _Reader(self.source, v, self.key(name))

    def code(self, name: str, v: object | None = None) -> Code:
        v = self.raw(name) if v is None else v
        if isinstance(v, str) and v in Code.__members__:
            return Code[v]
        if isinstance(v, int) and not isinstance(v, bool) and v in {int(c) for c in Code}:
            return Code(v)
        raise self.fail(name, v, "an event or job error name (e.g. EV_GEAR_CHANGED) or number")


_LISTS = ("start", "faults", "hints", "checks", "vary")


def parse_exercise(text: str, source: str) -> Exercise:
    """Parse and validate an exercise file; raises ExerciseError naming `source`."""
    if len(text) > MAX_FILE_CHARS:
        raise ExerciseError(source, "", None, f"at most {MAX_FILE_CHARS} characters")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:  # its message carries the line and column
        raise ExerciseError(source, "", None, f"TOML syntax: {e}") from None
    r = _Reader(source, doc, "")
    top = ("id", "title", "summary", "task", "par_time_s", "machine", "locked_assistants")
    r.only((*top, *_LISTS))
    machine = r.text("machine", 32)
    if machine not in MACHINES:
        raise r.fail("machine", machine, f"one of {', '.join(MACHINES)}")
    checks = tuple(_check(c) for c in r.items("checks"))
    if not checks:
        raise r.fail("checks", [], "at least one check")
    seen: set[str] = set()
    for i, c in enumerate(checks):
        if c.id in seen:
            raise ExerciseError(source, f"checks[{i}].id", c.id, "unique among the checks")
        seen.add(c.id)
    _requirements(source, checks)
    faults = tuple(_fault(f) for f in r.items("faults"))
    for i, c in enumerate(checks):
        if isinstance(c.rule, FindingCheck):
            _findable(source, f"checks[{i}].fault", c.rule, faults)
    start = tuple(_start_value(s) for s in r.items("start"))
    return Exercise(
        id=r.text("id", 64, ID_RE),
        title=r.text("title", MAX_TITLE),
        summary=r.text("summary", MAX_SUMMARY),
        task=r.text("task", MAX_TASK),
        par_time_s=r.number("par_time_s", 0.0, MAX_PAR_TIME_S, lo_open=True),
        machine=machine,
        start=start,
        faults=faults,
        hints=tuple(_hint(h) for h in r.items("hints")),
        checks=checks,
        locked=_locked(r),
        vary=_variation(r, faults, start),
    )


_ASSISTANT_NAMES = tuple(sorted(a.name for a in ASSISTANTS))


def _locked(r: _Reader) -> tuple[str, ...]:
    """The assistants the exercise locks: each one of the service's."""
    if not r.has("locked_assistants"):
        return ()
    v = r.raw("locked_assistants")
    allowed = f"a list of assistants: {', '.join(_ASSISTANT_NAMES)}"
    if not isinstance(v, list) or len(v) > len(_ASSISTANT_NAMES):
        raise r.fail("locked_assistants", v, allowed)
    for i, name in enumerate(v):
        if name not in _ASSISTANT_NAMES:
            raise r.fail(f"locked_assistants[{i}]", name, f"one of {', '.join(_ASSISTANT_NAMES)}")
    return tuple(dict.fromkeys(v))


def _variation(
    r: _Reader, faults: tuple[FaultSpec, ...], start: tuple[StartValue, ...]
) -> tuple[Vary, ...]:
    """The numbers drawn per seat: each a number of a fault or a starting value, its range
    within what the field takes (checked at both ends), once each."""
    out: list[Vary] = []
    for t in r.items("vary"):
        t.only(("key", "min", "max", "step"))
        key = t.text("key", 64)
        m = KEY_RE.fullmatch(key)
        if m is None:
            raise t.fail("key", key, "faults[i].<field> or start[i].value")
        section, index, name = m.group(1), int(m.group(2)), m.group(3)
        items: tuple[object, ...] = faults if section == "faults" else start
        if index >= len(items):
            raise t.fail("key", key, f"an entry of [[{section}]] (it has {len(items)})")
        lo = t.number("min", -1e9, 1e9)
        hi = t.number("max", lo, 1e9, lo_open=True)
        step = t.number("step", 0.0, hi - lo, lo_open=True)
        if (hi - lo) / step > MAX_STEPS:
            raise t.fail("step", step, f"at least (max − min)/{MAX_STEPS}")
        if section == "faults":
            fault = faults[index].fault
            fields = _fields(type(fault))
            if name == "axis" or name not in fields or isinstance(getattr(fault, name), str):
                numbers = [f for f in fields if f != "axis" and f not in ("gear", "code", "codes")]
                raise t.fail("key", key, f"a number of {fault.kind}: {', '.join(numbers)}")
            typ, optional = fields[name]
            for end, which in ((lo, "min"), (hi, "max")):  # both within what the field takes
                try:
                    _field(_Reader(r.source, {name: end}, ""), name, typ, optional)
                except ExerciseError as e:
                    raise t.fail(which, end, f"{name}: {e.allowed}") from None
        elif name != "value" or not isinstance(start[index].value, int | float):
            raise t.fail("key", key, "start[i].value of a numeric starting value")
        if any(v.key == key for v in out):
            raise t.fail("key", key, "each number varied once")
        kind: typing.Literal["faults", "start"] = "faults" if section == "faults" else "start"
        out.append(Vary(key, kind, index, name, lo, hi, step))
    return tuple(out)


def _start_value(r: _Reader) -> StartValue:
    r.only(("scope", "target", "name", "value"))
    scope_text = r.text("scope", 16)
    scopes = [s.value for s in Scope]
    if scope_text not in scopes:
        raise r.fail("scope", scope_text, f"one of {', '.join(scopes)}")
    scope = Scope(scope_text)
    target = ""
    if scope is Scope.AXIS:
        target = r.axis("target")
    elif r.has("target"):
        raise r.fail("target", r.raw("target"), "only for axis scope")
    name = r.text("name", 128)
    try:
        resolve(scope, name)
    except ParamError as e:
        raise r.fail("name", name, str(e)) from None
    value = r.raw("value")
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise r.fail("value", value, "a number or a string, in the list's unit")
    return StartValue(scope, target, name, value)


_FAULTS: dict[str, type[Fault]] = {cls.kind: cls for cls in CATALOGUE}


def _fault(r: _Reader) -> FaultSpec:
    kind = r.text("kind", 64)
    cls = _FAULTS.get(kind)
    if cls is None:
        raise r.fail("kind", kind, f"one of {', '.join(sorted(_FAULTS))}")
    fields = _fields(cls)
    r.only(("kind", "trigger", *fields))
    args = {name: _field(r, name, typ, opt) for name, (typ, opt) in fields.items()}
    args = {k: v for k, v in args.items() if v is not None}
    trigger = NOW
    if r.has("trigger"):
        t = r.sub("trigger")
        t.only(("after_s", "on_motion"))
        trigger = Trigger(
            after_s=t.number("after_s", 0.0, MAX_PAR_TIME_S) if t.has("after_s") else 0.0,
            on_motion=t.flag("on_motion") if t.has("on_motion") else False,
        )
    return FaultSpec(cls(**args), trigger)


def _findable(source: str, key: str, rule: FindingCheck, faults: tuple[FaultSpec, ...]) -> None:
    """A finding names a kind of fault that can be found and that the exercise hides."""
    if rule.fault not in FINDABLE:
        raise ExerciseError(source, key, rule.fault, f"one of {', '.join(sorted(FINDABLE))}")
    cls = FINDABLE[rule.fault][0]
    if not any(isinstance(f.fault, cls) for f in faults):
        raise ExerciseError(source, key, rule.fault, "a fault of this kind among the [[faults]]")


def _hint(r: _Reader) -> Hint:
    r.only(("text", "cost"))
    return Hint(r.text("text", MAX_TEXT), r.number("cost", 0.0, MAX_POINTS))


_RULES: dict[str, type[Rule]] = {cls.kind: cls for cls in RULES}


def _check(r: _Reader) -> Check:
    kind = r.text("kind", 64)
    cls = _RULES.get(kind)
    if cls is None:
        raise r.fail("kind", kind, f"one of {', '.join(sorted(_RULES))}")
    fields = _fields(cls)
    r.only(("id", "text", "points", "kind", "requires", *fields))
    args = {name: _field(r, name, typ, opt) for name, (typ, opt) in fields.items()}
    rule = cls(**{k: v for k, v in args.items() if v is not None})
    requires: tuple[str, ...] = ()
    if r.has("requires"):
        v = r.raw("requires")
        if not isinstance(v, list) or not all(isinstance(x, str) and ID_RE.match(x) for x in v):
            raise r.fail("requires", v, "a list of the ids of other checks")
        requires = tuple(v)
    return Check(
        id=r.text("id", 64, ID_RE),
        text=r.text("text", MAX_TEXT),
        points=r.number("points", 0.0, MAX_POINTS, lo_open=True),
        rule=rule,
        requires=requires,
    )


def _requirements(source: str, checks: tuple[Check, ...]) -> None:
    """What a check requires are other checks the monitor judges, themselves requiring
    nothing (one level: no cycles, and what counts is plain to the student)."""
    by_id = {c.id: c for c in checks}
    for i, c in enumerate(checks):
        for r in c.requires:
            other = by_id.get(r)
            key = f"checks[{i}].requires"
            if other is None or other is c:
                raise ExerciseError(source, key, r, "the id of another check of the exercise")
            if other.requires or isinstance(other.rule, FindingCheck):
                raise ExerciseError(source, key, r, "a check that requires nothing, not a finding")
        if c.requires and isinstance(c.rule, FindingCheck):
            key = f"checks[{i}].requires"
            raise ExerciseError(source, key, list(c.requires), "none for a finding")


def _fields(cls: type) -> dict[str, tuple[object, bool]]:
    """A dataclass' fields: name -> (type, has a default)."""
    hints = typing.get_type_hints(cls)
    return {
        f.name: (hints[f.name], f.default is not dataclasses.MISSING)
        for f in dataclasses.fields(cls)
    }


def _field(r: _Reader, name: str, typ: object, optional: bool) -> Any:
    """One field of a fault or check from its type: axis names by their form, gear stages
    1..6, codes by name or number, durations and tolerances positive."""
    if not r.has(name):
        if optional:
            return None
        raise r.fail(name, None, "missing")
    if name in ("axis", "against"):
        return r.axis(name)
    if name == "gear":
        return r.integer(name, 1, 6)
    if name == "code":
        return r.code(name)
    if name == "codes":
        v = r.raw(name)
        if not isinstance(v, list) or not v or len(v) > MAX_ITEMS:
            raise r.fail(name, v, f"a list of 1..{MAX_ITEMS} event or job error names")
        return tuple(_code_at(r, name, i, c) for i, c in enumerate(v))
    if name == "window_s":
        return r.number(name, 0.0, MAX_WINDOW_S, lo_open=True)
    if name == "within_pct":
        return r.number(name, 0.0, 100.0, lo_open=True)
    if name == "busy_pct":
        return r.number(name, 0.0, 100.0)
    if name == "attempts":
        return r.integer(name, 1, 10)
    if name == "template":
        return r.integer(name, min(TEMPLATES), max(TEMPLATES))
    if name == "bandwidth_pct":
        return r.number(name, 0.0, 100.0)
    if name in ("tolerance", "factor", "rms", "delay_s", "v_loss", "width", "speed_rpm"):
        return r.number(name, 0.0, 1e9, lo_open=True)
    base = typing.get_args(typ) or (typ,)
    if bool in base:
        return r.flag(name)
    if float in base:
        return r.number(name, -1e9, 1e9)
    if int in base:
        return r.integer(name, -(2**31), 2**31 - 1)
    return r.text(name, 128)


def _code_at(r: _Reader, name: str, i: int, v: object) -> Code:
    try:
        return r.code(name, v)
    except ExerciseError:
        raise ExerciseError(
            r.source, f"{r.key(name)}[{i}]", v, "an event or job error name or number"
        ) from None
