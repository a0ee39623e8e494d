"""Parameter registry: what each parameter is, its range, unit, default and when it applies.

Entries come from the manuals (IDs such as P-AXIS-00099, list names such as
`getriebe[i].kv`). Where the manuals give no ID for something the simulation needs, the entry
has our own ID (`INB-...`) and `source="inbetrieb"`.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import StrEnum

from nc_sim.units import AxisKind, Quantity, display_unit, eng_unit, raw_unit


class Scope(StrEnum):
    """Which parameter list a parameter lives in."""

    AXIS = "axis"
    CHANNEL = "channel"
    TOOL = "tool"


class Effect(StrEnum):
    """When a changed value takes effect."""

    NOW = "now"
    RESET = "reset"
    RESTART = "restart"


class DType(StrEnum):
    """Data types as the manuals name them."""

    UNS16 = "UNS16"
    UNS32 = "UNS32"
    SGN16 = "SGN16"
    SGN32 = "SGN32"
    REAL64 = "REAL64"
    BOOLEAN = "BOOLEAN"
    STRING = "STRING"
    ENUM = "ENUM"  # string constant with a numeric code (achs_typ, operation_mode)
    FLAGS = "FLAGS"  # OR of string constants or a hex value (synchronisation types)


DTYPE_LIMITS: dict[DType, tuple[float, float]] = {
    DType.UNS16: (0, 65535),
    DType.UNS32: (0, 4294967295),
    DType.SGN16: (-32768, 32767),
    DType.SGN32: (-2147483648, 2147483647),
    DType.REAL64: (-1.7976931348623157e308, 1.7976931348623157e308),
    DType.BOOLEAN: (0, 1),
    DType.ENUM: (0, 4294967295),
    DType.FLAGS: (0, 4294967295),
}

# A bound is a number or a reference to another parameter of the same list, optionally scaled.
Bound = float | str | None


@dataclass(frozen=True)
class ParamDef:
    """One parameter as the manuals define it.

    `name` is the list name with `[i]` / `[j]` placeholders for indices, e.g.
    `getriebe[i].kv` or `spindel[i].range_table[j].min_speed`.
    """

    id: str
    name: str
    scope: Scope
    dtype: DType
    quantity: Quantity
    default: float | str
    lo: Bound = None
    hi: Bound = None
    effect: Effect = Effect.NOW
    axis_types: str = "TRS"
    title: str = ""
    source: str = "manual"
    symbols: dict[str, int] = field(default_factory=dict)
    # why the simulation accepts it without any effect (empty: it acts, and a test shows how)
    without_effect: str = ""

    @property
    def per_gear(self) -> bool:
        """True for entries of the gear records `getriebe[0..5]`."""
        return self.name.startswith("getriebe[")

    @property
    def is_numeric(self) -> bool:
        return self.dtype not in (DType.STRING,)

    def raw_unit(self, kind: AxisKind) -> str:
        """Unit of the value in the list."""
        return raw_unit(self.quantity, kind)

    def eng_unit(self, kind: AxisKind) -> str:
        """Unit of the value as the kernel uses it."""
        return eng_unit(self.quantity, kind)

    def display_unit(self, kind: AxisKind) -> tuple[float, str]:
        """(factor from the list value, unit) as the HMI shows the value (units.display_unit)."""
        return display_unit(self.quantity, kind)


_INDEX_RE = re.compile(r"\[(\d+|i|j)\]")


def normalise_name(name: str) -> tuple[str, tuple[int, ...]]:
    """Split `getriebe[2].kv` into the registry key `getriebe[].kv` and the indices (2,)."""
    indices = tuple(int(m) for m in re.findall(r"\[(\d+)\]", name))
    return _INDEX_RE.sub("[]", name), indices


class Registry:
    """Lookup of parameter definitions by ID and by list name."""

    def __init__(self, defs: list[ParamDef]) -> None:
        self._by_key: dict[tuple[Scope, str], ParamDef] = {}
        self._by_id: dict[str, ParamDef] = {}
        for d in defs:
            key = (d.scope, normalise_name(d.name)[0])
            if key in self._by_key or d.id in self._by_id:
                raise ValueError(f"duplicate parameter definition {d.id} {d.name}")
            self._by_key[key] = d
            self._by_id[d.id] = d

    def __iter__(self) -> Iterator[ParamDef]:
        return iter(self._by_id.values())

    def __len__(self) -> int:
        return len(self._by_id)

    def by_id(self, pid: str) -> ParamDef:
        """The definition with this ID; KeyError when unknown."""
        return self._by_id[pid]

    def lookup(self, scope: Scope, name: str) -> tuple[ParamDef, tuple[int, ...]] | None:
        """Definition and indices for a concrete list name such as `getriebe[0].kv`."""
        key, idx = normalise_name(name)
        d = self._by_key.get((scope, key))
        if d is None:
            return None
        return d, idx
