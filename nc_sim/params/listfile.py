"""The controller's native parameter list format.

One entry per line: `<name> <value>` with optional `# comment`; `#` also starts a comment
line. Values are decimal, hex (`0x0004`), string constants (`ACHSTYP_SPINDEL`), OR-ed
constants (`PLC_INFO | MVS_SVS`) or plain strings (`spindel[0].bezeichnung S1`). The manuals'
excerpts also carry unit annotations in brackets after the value (`1400 [°/s*s]`); those are
kept as part of the comment.

`parse_list` keeps every line, so `ParamList.text()` reproduces the input exactly; a list
with any bad line raises `ParamListError` naming every bad line, and nothing of it is applied.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from nc_sim.params.curves import curve_problems
from nc_sim.params.definitions import registry
from nc_sim.params.registry import (
    DTYPE_LIMITS,
    DType,
    ParamDef,
    Registry,
    Scope,
)
from nc_sim.params.whole_list import modulo_problems, share_problems
from nc_sim.units import AxisKind

Value = float | int | str

# Numbers as the controller writes them: ASCII digits only (no full-width digits, no `2_000`
# as Python would take), decimal or 0x hex integers, decimal reals with an optional exponent.
_INT = re.compile(r"[+-]?(?:0[xX](?P<hex>[0-9a-fA-F]+)|(?P<dec>[0-9]+))")
_REAL = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_MAX_NUMBER_CHARS = 1000  # far beyond any value a list holds; keeps int() cheap

# how many records an indexed name may address
_INDEX_LIMITS = {
    "getriebe": 6,
    "spindel": 6,
    "range_table": 6,
    "lr_hw": 1,
    "achse": 32,
    "wz": 1000,
    "m_synch": 1000,  # M0 … M999
}


class ParamError(ValueError):
    """One rejected parameter value: names the line (if any), the parameter and the range."""

    def __init__(
        self,
        message: str,
        *,
        name: str = "",
        line: int | None = None,
        limits: tuple[float, float, str] | None = None,
    ) -> None:
        self.name = name
        self.line = line
        self.detail = message
        self.limits = limits  # (lo, hi, unit) for a value out of range
        super().__init__(f"line {line}: {message}" if line is not None else message)


class ParamListError(ValueError):
    """A list with one or more bad lines; nothing of it was applied."""

    def __init__(self, errors: list[ParamError]) -> None:
        self.errors = errors
        super().__init__("; ".join(str(e) for e in errors))


@dataclass
class ListLine:
    """One line of a list as written, with the parsed entry when it is one."""

    raw: str
    name: str | None = None
    value_text: str | None = None
    comment: str = ""


@dataclass
class ParamList:
    """A parsed list: the lines as written plus the typed values."""

    scope: Scope
    lines: list[ListLine] = field(default_factory=list)
    values: dict[str, Value] = field(default_factory=dict)

    def text(self) -> str:
        """The list exactly as it was read (lossless round trip)."""
        return "".join(line.raw for line in self.lines)


def _split_comment(rest: str) -> tuple[str, str]:
    """Split `value  # comment` or `value [unit]`; returns (value, comment-with-separator)."""
    for marker in ("#", "["):
        pos = rest.find(marker)
        if pos >= 0:
            return rest[:pos].rstrip(), rest[pos:]
    return rest.rstrip(), ""


def _check_indices(d: ParamDef, name: str, indices: tuple[int, ...]) -> None:
    parts = re.findall(r"(\w+)\[(\d+)\]", name)
    for part, idx in parts:
        limit = _INDEX_LIMITS.get(part)
        if limit is not None and int(idx) >= limit:
            raise ParamError(
                f"{name}: index {idx} of {part}[] must be 0 … {limit - 1} ({d.id})", name=name
            )


def parse_value(d: ParamDef, name: str, text: str) -> Value:
    """Parse the value text of one entry according to its definition."""
    text = text.strip()
    if d.dtype is DType.STRING:
        return text
    if not text:
        raise ParamError(f"{name}: value missing ({d.id})", name=name)
    if d.dtype in (DType.ENUM, DType.FLAGS):
        code = 0
        for token in (t.strip() for t in text.split("|")):
            if token in d.symbols:
                code |= d.symbols[token]
                continue
            number = _integer(token)
            if number is None:
                allowed = ", ".join(d.symbols)
                raise ParamError(f"{name}: '{token}' is not one of {allowed} ({d.id})", name=name)
            code |= number
            if d.dtype is DType.ENUM:
                break
        return _within_type(d, name, code)
    whole = _integer(text)
    if whole is not None:
        return _within_type(d, name, whole)
    if len(text) > _MAX_NUMBER_CHARS or not _REAL.fullmatch(text):
        shown = text if len(text) <= 40 else text[:40] + "…"
        raise ParamError(f"{name}: '{shown}' is not a number ({d.id})", name=name)
    value = float(text)
    if not math.isfinite(value):
        raise ParamError(f"{name}: '{text}' is not a finite number ({d.id})", name=name)
    if d.dtype is not DType.REAL64 and value != int(value):
        raise ParamError(
            f"{name}: {d.dtype.value} takes whole numbers, not {text} ({d.id})", name=name
        )
    return _within_type(d, name, value)


def _integer(text: str) -> int | None:
    """A decimal or 0x hex integer, or None when `text` is not one."""
    m = _INT.fullmatch(text)
    if m is None or len(text) > _MAX_NUMBER_CHARS:
        return None
    magnitude = int(m["hex"], 16) if m["hex"] else int(m["dec"], 10)
    return -magnitude if text.startswith("-") else magnitude


def _within_type(d: ParamDef, name: str, value: int | float) -> int | float:
    """`value` when its data type holds it (a 300-digit integer is refused here, not by an
    OverflowError further on)."""
    lo_t, hi_t = DTYPE_LIMITS[d.dtype]
    if not lo_t <= value <= hi_t:  # int against float compares exactly, without overflow
        digits = str(value)
        shown = digits if len(digits) <= 24 else f"{digits[:20]}… ({len(digits)} digits)"
        # the parameter's own range, as the editor shows it (a bound that names another
        # entry is not known here: the type's limit stands in for it)
        lo = max(d.lo, lo_t) if isinstance(d.lo, int | float) else lo_t
        hi = min(d.hi, hi_t) if isinstance(d.hi, int | float) else hi_t
        units = {d.raw_unit(k) for k in AxisKind}  # named when the axis kind does not matter
        unit = units.pop() if len(units) == 1 else ""
        span = f"{_fmt(lo)} … {_fmt(hi)}" + (f" {unit}" if unit else "")
        raise ParamError(
            f"{name} = {shown} is out of range {span} ({d.id})",
            name=name,
            limits=(lo, hi, unit),
        )
    return value


def format_value(d: ParamDef, value: Value) -> str:
    """Canonical text of a value: symbols for enums and flags, integers without a dot."""
    if d.dtype is DType.STRING:
        return str(value)
    if d.dtype in (DType.ENUM, DType.FLAGS):
        code = int(value)
        if d.dtype is DType.ENUM:
            for sym, c in d.symbols.items():
                if c == code:
                    return sym
            return f"0x{code:04X}"
        names = [s for s, c in d.symbols.items() if c and code & c == c]
        if code == 0:
            return next((s for s, c in d.symbols.items() if c == 0), "0")
        if sum(d.symbols[s] for s in names) == code:
            return " | ".join(reversed(names))
        return f"0x{code:08X}"
    v = float(value)
    if d.dtype is not DType.REAL64 or (v == int(v) and abs(v) < 1e15):
        return str(int(v))
    return repr(v)


def _resolve_bound(
    bound: float | str | None,
    d: ParamDef,
    name: str,
    lookup: Mapping[str, Value],
    reg: Registry,
) -> float | None:
    if bound is None or isinstance(bound, int | float):
        return None if bound is None else float(bound)
    factor = 1.0
    ref_id = bound
    if "*" in bound:
        f, ref_id = bound.split("*")
        factor = float(f)
    ref = reg.by_id(ref_id)
    ref_name = concrete_name(ref.name, name)
    ref_val = lookup.get(ref_name, ref.default)
    return factor * float(ref_val) if not isinstance(ref_val, str) else None


def concrete_name(template: str, context: str) -> str:
    """Fill `[i]`/`[j]` of a template with the indices of a concrete name (gear 0 if none)."""
    indices = [int(i) for i in re.findall(r"\[(\d+)\]", context)]
    it = iter(indices)

    def fill(_m: re.Match[str]) -> str:
        return f"[{next(it, 0)}]"

    return re.sub(r"\[(?:i|j)\]", fill, template)


def axis_kind_of(values: Mapping[str, Value]) -> AxisKind:
    """Axis kind from `kenngr.achs_typ` in an axis list (linear when absent)."""
    code = int(values.get("kenngr.achs_typ", 1))
    return {2: AxisKind.ROTARY, 4: AxisKind.SPINDLE}.get(code, AxisKind.LINEAR)


def value_range(
    d: ParamDef, name: str, lookup: Mapping[str, Value], reg: Registry | None = None
) -> tuple[float, float]:
    """Allowed range of a numeric entry in list units, bounds that name other parameters
    taken from `lookup` (the list as it stands), clipped to the data type's limits."""
    reg = reg or registry()
    lo_t, hi_t = DTYPE_LIMITS[d.dtype]
    lo = _resolve_bound(d.lo, d, name, lookup, reg)
    hi = _resolve_bound(d.hi, d, name, lookup, reg)
    return (lo_t if lo is None else max(lo, lo_t)), (hi_t if hi is None else min(hi, hi_t))


def check_range(
    d: ParamDef,
    name: str,
    value: Value,
    lookup: Mapping[str, Value],
    kind: AxisKind,
    reg: Registry | None = None,
) -> None:
    """Raise ParamError when value is outside its range (including referenced bounds)."""
    if isinstance(value, str) or d.dtype is DType.STRING:
        return
    lo, hi = value_range(d, name, lookup, reg)
    if not lo <= float(value) <= hi:
        unit = d.raw_unit(kind)
        span = f"{_fmt(lo)} … {_fmt(hi)}" + (f" {unit}" if unit else "")
        refs = [b for b in (d.lo, d.hi) if isinstance(b, str)]
        why = f" (limited by {', '.join(refs)})" if refs else ""
        raise ParamError(
            f"{name} = {_fmt(float(value))} is out of range {span}{why} ({d.id})",
            name=name,
            limits=(lo, hi, unit),
        )


def _fmt(x: float) -> str:
    return str(int(x)) if x == int(x) and abs(x) < 1e16 else f"{x:g}"


def resolve(scope: Scope, name: str, reg: Registry | None = None) -> ParamDef:
    """The definition for a concrete name; ParamError when the name is unknown."""
    reg = reg or registry()
    found = reg.lookup(scope, name)
    if found is None:
        raise ParamError(f"unknown {scope.value} parameter '{name}'", name=name)
    d, idx = found
    _check_indices(d, name, idx)
    return d


def validate_values(
    scope: Scope, values: Mapping[str, Value], lines: Mapping[str, int] | None = None
) -> list[ParamError]:
    """Check every value against its range, with referenced bounds taken from `values`."""
    reg = registry()
    kind = axis_kind_of(values) if scope is Scope.AXIS else AxisKind.LINEAR
    errors: list[ParamError] = []
    for name, value in values.items():
        try:
            check_range(resolve(scope, name, reg), name, value, values, kind, reg)
        except ParamError as e:
            e.line = (lines or {}).get(name)
            errors.append(ParamError(e.detail, name=name, line=e.line, limits=e.limits))
    if scope is Scope.AXIS and not errors:  # the list as a whole: curves, modulo, G201 shares
        checks = (curve_problems, modulo_problems, share_problems)
        for name, message in [p for check in checks for p in check(values, reg)]:
            errors.append(ParamError(message, name=name, line=(lines or {}).get(name)))
    return errors


def parse_list(text: str, scope: Scope) -> ParamList:
    """Parse a whole list; raises ParamListError naming every bad line."""
    reg = registry()
    plist = ParamList(scope)
    errors: list[ParamError] = []
    line_of: dict[str, int] = {}
    for lineno, raw in enumerate(text.splitlines(keepends=True), start=1):
        line = ListLine(raw)
        plist.lines.append(line)
        body = raw.strip()
        if not body or body.startswith("#"):
            continue
        name, _, rest = body.partition(" ") if " " in body else body.partition("\t")
        rest = rest.strip()
        try:
            d = resolve(scope, name, reg)
            if d.dtype is DType.STRING:  # a string may contain '[' but not '#'
                value_text, sep, cmt = rest.partition("#")
                value_text, comment = value_text.rstrip(), sep + cmt
            else:
                value_text, comment = _split_comment(rest)
            value = parse_value(d, name, value_text)
        except ParamError as e:
            errors.append(ParamError(e.detail, name=e.name or name, line=lineno))
            continue
        if name in line_of:  # last one winning would silently drop a value
            msg = f"{name} is already set in line {line_of[name]} ({d.id})"
            errors.append(ParamError(msg, name=name, line=lineno))
            continue
        line.name, line.value_text, line.comment = name, value_text, comment
        plist.values[name] = value
        line_of[name] = lineno
    errors.extend(validate_values(scope, plist.values, line_of))
    if errors:
        raise ParamListError(sorted(errors, key=lambda e: e.line or 0))
    return plist


def format_list(values: Mapping[str, Value], scope: Scope, header: Iterable[str] = ()) -> str:
    """Write values in the native format, one `name value` per line, with the ID as comment."""
    reg = registry()
    out = [f"# {h}\n" for h in header]
    width = max((len(n) for n in values), default=0)
    for name, value in values.items():
        d = resolve(scope, name, reg)
        out.append(f"{name.ljust(width)} {format_value(d, value)}  # {d.id}\n")
    return "".join(out)
