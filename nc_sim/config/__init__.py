"""Machine configuration built from parameter lists: one channel, its axes and spindles."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources

from nc_sim.errors import NcUsageError
from nc_sim.params import ParamListError, Scope, Value, parse_list, registry, resolve
from nc_sim.params.listfile import axis_kind_of, concrete_name, validate_values
from nc_sim.units import AxisKind, Quantity, to_eng


@dataclass
class AxisConfig:
    """One axis or spindle: its name in the channel and its parameter values."""

    name: str
    values: dict[str, Value] = field(default_factory=dict)

    @property
    def kind(self) -> AxisKind:
        return axis_kind_of(self.values)

    @property
    def is_spindle(self) -> bool:
        return self.kind is AxisKind.SPINDLE

    def _lookup(self, name: str, gear: int) -> tuple[Quantity, Value]:
        concrete = concrete_name(_gear_template(name), f"[{gear - 1}]")
        d = resolve(Scope.AXIS, concrete)
        return d.quantity, self.values.get(concrete, d.default)

    def raw(self, name: str, gear: int = 1) -> Value:
        """Raw value of a parameter (default when unset); `[i]` of gear records = gear - 1."""
        return self._lookup(name, gear)[1]

    def eng(self, name: str, gear: int = 1) -> float:
        """Value in the kernel's engineering unit (mm, °, s based)."""
        quantity, raw = self._lookup(name, gear)
        if isinstance(raw, str):
            raise NcUsageError(f"{name} is not numeric")
        return to_eng(quantity, float(raw))

    def flag(self, name: str, gear: int = 1) -> bool:
        return bool(self.eng(name, gear))

    def ref(self, name: str, gear: int = 1) -> tuple[str, str]:
        """The concrete list name (`getriebe[0].kv` for gear 1) and the ID of a parameter."""
        concrete = concrete_name(_gear_template(name), f"[{gear - 1}]")
        return concrete, resolve(Scope.AXIS, concrete).id


def _gear_template(name: str) -> str:
    """Accept `getriebe.kv` or `getriebe[i].kv` as shorthand for the active gear record."""
    if name.startswith("getriebe."):
        return "getriebe[i]." + name[len("getriebe.") :]
    if name.startswith("lr_hw."):
        return "lr_hw[i]." + name[len("lr_hw.") :]
    return name


@dataclass
class MachineConfig:
    """A channel with its axes (path axes first, then spindles)."""

    name: str
    channel: dict[str, Value]
    axes: list[AxisConfig]
    tools: dict[str, Value] = field(default_factory=dict)  # wz[i].* tool dynamic data

    def channel_raw(self, name: str) -> Value:
        d = resolve(Scope.CHANNEL, name)
        return self.channel.get(name, d.default)

    def channel_eng(self, name: str) -> float:
        d = resolve(Scope.CHANNEL, name)
        raw = self.channel.get(name, d.default)
        return to_eng(d.quantity, float(raw)) if not isinstance(raw, str) else 0.0

    def tool_eng(self, name: str) -> float:
        """Tool parameter `wz[i].*` in engineering units (default when unset)."""
        d = resolve(Scope.TOOL, name)
        raw = self.tools.get(name, d.default)
        return to_eng(d.quantity, float(raw)) if not isinstance(raw, str) else 0.0

    @property
    def cycle_s(self) -> float:
        return self.channel_eng("cycle_time")

    def list_values(self, scope: Scope, target: str = "") -> dict[str, Value]:
        """The live dict of written values of one list (channel, tool, or axis `target`)."""
        if scope is Scope.CHANNEL:
            return self.channel
        if scope is Scope.TOOL:
            return self.tools
        return self.axis(target).values

    def axis(self, name: str) -> AxisConfig:
        for a in self.axes:
            if a.name == name:
                return a
        raise NcUsageError(f"no axis {name}")

    @property
    def main_spindle(self) -> str | None:
        """Configured name of the main spindle (of the spdl_anzahl spindel[i], the one whose
        log_achs_nr is main_spindle_ax_nr)."""
        nr = self.channel_raw("main_spindle_ax_nr")
        for i in range(int(self.channel.get("spdl_anzahl", 0))):
            if self.channel.get(f"spindel[{i}].log_achs_nr") == nr and nr:
                return str(self.channel.get(f"spindel[{i}].bezeichnung", f"S{i + 1}"))
        return None


# (scope, target, list name, value): one parameter value to write into a machine's lists
ValueWrite = tuple[str, str, str, Value]


def apply_values(
    cfg: MachineConfig, values: Iterable[ValueWrite], *, skip_missing_axes: bool = False
) -> None:
    """Write values into a machine's lists: the one way values get there, in the gateway's
    copy and the worker's machine alike. NcUsageError for an axis the machine does not
    have, unless `skip_missing_axes` (stored values of an axis the lists no longer
    define)."""
    for scope, target, name, value in values:
        try:
            cfg.list_values(Scope(scope), target)[name] = value
        except NcUsageError:
            if not skip_missing_axes:
                raise


def _axis_numbers(channel: Mapping[str, Value]) -> list[tuple[str, int, bool]]:
    """(name, logical axis number, is_spindle) for every axis the channel list declares."""
    out: list[tuple[str, int, bool]] = []
    for i in range(32):
        name = channel.get(f"achse[{i}].bezeichnung")
        if name is not None:
            out.append((str(name), int(channel.get(f"achse[{i}].log_achs_nr", i + 1)), False))
    for i in range(int(channel.get("spdl_anzahl", 0))):
        nr = int(channel.get(f"spindel[{i}].log_achs_nr", 0))
        out.append((str(channel.get(f"spindel[{i}].bezeichnung", f"S{i + 1}")), nr, True))
    return out


def machine_from_lists(
    name: str, channel_text: str, axis_texts: Mapping[int, str], tool_text: str = ""
) -> MachineConfig:
    """Build a machine from a channel list, axis lists keyed by logical axis number and an
    optional tool list (dynamic data wz[i].*).

    Raises ParamListError (with line numbers) for a bad list, NcUsageError for a channel that
    names an axis with no list.
    """
    channel = parse_list(channel_text, Scope.CHANNEL).values
    by_nr: dict[int, dict[str, Value]] = {}
    for nr, text in axis_texts.items():
        by_nr[nr] = parse_list(text, Scope.AXIS).values
    axes = []
    for ax_name, nr, spindle in _axis_numbers(channel):
        if nr not in by_nr:
            raise NcUsageError(f"channel names axis {ax_name} (log_achs_nr {nr}) with no axis list")
        values = dict(by_nr[nr])
        if spindle and axis_kind_of(values) is not AxisKind.SPINDLE:
            raise NcUsageError(f"{ax_name}: spindel[] entry needs kenngr.achs_typ ACHSTYP_SPINDEL")
        axes.append(AxisConfig(ax_name, values))
    tools = parse_list(tool_text, Scope.TOOL).values if tool_text else {}
    return MachineConfig(name, channel, axes, tools)


def demo_lists() -> tuple[str, dict[int, str]]:
    """The shipped demo lathe: channel list and axis lists (package data, read-only)."""
    base = resources.files("nc_sim.config") / "demo"
    channel = (base / "channel.lis").read_text(encoding="utf-8")
    axes: dict[int, str] = {}
    for entry in base.iterdir():
        if entry.name.startswith("axis_") and entry.name.endswith(".lis"):
            axes[int(entry.name[5:-4])] = entry.read_text(encoding="utf-8")
    return channel, axes


def demo_machine() -> MachineConfig:
    """The demo lathe: main spindle S1 with six gear ranges, linear axes X and Z."""
    channel, axes = demo_lists()
    tools = (resources.files("nc_sim.config") / "demo" / "tools.lis").read_text(encoding="utf-8")
    return machine_from_lists("demo", channel, axes, tools)


def apply_overrides(
    cfg: MachineConfig, scope: Scope, target: str, values: Mapping[str, Value]
) -> None:
    """Apply parameter values to a config; the whole set is validated before anything changes."""
    if scope is Scope.CHANNEL:
        merged = {**cfg.channel, **values}
        errors = validate_values(scope, merged)
        if errors:
            raise ParamListError(errors)
        cfg.channel.update(values)
        return
    axis = cfg.axis(target)
    merged = {**axis.values, **values}
    errors = validate_values(scope, merged)
    if errors:
        raise ParamListError(errors)
    axis.values.update(values)


__all__ = [
    "AxisConfig",
    "MachineConfig",
    "Quantity",
    "apply_overrides",
    "demo_machine",
    "machine_from_lists",
    "registry",
]
