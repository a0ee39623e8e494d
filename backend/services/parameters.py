"""Parameters of a hosted machine: read with metadata, write validated and audited, import
and export the native list format, and apply pending values at reset or restart.

A write is all or nothing: every value is checked against its range with the bounds taken
from the list as it would stand afterwards; a rejection names parameter, range and unit.
Values that take effect now go to the running machine at once; the others are stored and
shown as pending until reset (`Effect.RESET`) or restart (`Effect.RESTART`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping

from api.common import ParameterProblem, StaleValue
from api.parameters import (
    AppliedChange,
    AuditEntry,
    ParameterChange,
    ParameterValue,
    ParameterWriteResult,
)
from backend.errors import ApiError, Conflict, Forbidden, Invalid
from backend.services.auth import Actor
from backend.services.machines import MachineProxy
from backend.services.pending import Pending
from backend.services.store import Store, StoredChange, parameter_entry
from backend.workers.protocol import ApplyValues, Values
from nc_sim.config import apply_values
from nc_sim.params import (
    Effect,
    ParamDef,
    ParamError,
    ParamListError,
    Scope,
    Value,
    format_list,
    parse_list,
    registry,
    resolve,
    validate_values,
)
from nc_sim.params.listfile import axis_kind_of, parse_value, value_range
from nc_sim.params.registry import normalise_name
from nc_sim.units import AxisKind

Key = tuple[str, str, str]  # scope, target ('' for channel and tool), name
_GEAR = "getriebe[i]."
# an axis's indexed records and how many it has: six gear records, one control loop hardware
# record (lr_hw[0].vz_stellgr, vz_istw of 004 §3.5); each listed per record, written or not
_RECORDS = {_GEAR: 6, "lr_hw[i].": 1}
_KIND_LETTER = {AxisKind.LINEAR: "T", AxisKind.ROTARY: "R", AxisKind.SPINDLE: "S"}


def _target(m: MachineProxy, scope: Scope, target: str | None) -> str:
    if scope is not Scope.AXIS:
        return ""
    names = [ax.name for ax in m.cfg.axes]
    if target not in names:
        raise Invalid(f"axis parameters need a target, one of {', '.join(names)}")
    return target


def _problem(e: ParamError, scope: Scope, target: str, line: int | None = None) -> ParameterProblem:
    d = None
    with contextlib.suppress(ParamError):
        d = resolve(scope, e.name)
    lo, hi, unit = e.limits if e.limits else (None, None, None)
    return ParameterProblem(
        parameter=e.name,
        id=d.id if d else None,
        target=target or None,
        message=e.detail,
        line=line if line is not None else e.line,
        min=lo,
        max=hi,
        unit=unit,
    )


def _rejected(problems: list[ParameterProblem]) -> ApiError:
    first = problems[0].message if problems else "rejected"
    return Invalid(
        {
            "message": f"{len(problems)} parameter value(s) rejected, nothing applied: {first}",
            "problems": [p.model_dump() for p in problems],
        }
    )


def _parse(d: ParamDef, name: str, value: Value) -> Value:
    if isinstance(value, int | float) and d.is_numeric and not isinstance(value, bool):
        return parse_value(d, name, repr(value) if isinstance(value, float) else str(value))
    return parse_value(d, name, str(value))


def effective(m: MachineProxy, scope: Scope, target: str) -> dict[str, Value]:
    """A list as it stands with pending values: what the next restart would load."""
    values = dict(m.cfg.list_values(scope, target))
    for (s, t, n), p in m.pending.items():
        if s == scope.value and t == target:
            values[n] = p.value
    return values


PLANT = "sim."  # the simulated plant's parameters (motor, drive, encoder): not the NC's


def plant_hidden(actor: Actor) -> bool:
    """A class's student neither sees nor writes the simulated plant: their exercise is to
    find its faults from the NC's side, as on a real machine, which has no sim.* lists."""
    return actor.seat is not None


def write(
    actor: Actor,
    m: MachineProxy,
    store: Store,
    changes: list[ParameterChange],
    comment: str = "",
    lines: Mapping[str, int] | None = None,
) -> ParameterWriteResult:
    """Validate all changes together (refused when based on a value someone else has
    written since), then store, audit and apply them."""
    plant = [c.name for c in changes if c.name.startswith(PLANT)]
    if plant and plant_hidden(actor):
        raise Forbidden(f"{plant[0]}: the simulated plant is the instructor's on a class seat")
    with m.lock:
        problems: list[ParameterProblem] = []
        parsed: list[tuple[Scope, str, ParamDef, str, Value]] = []
        seen: set[Key] = set()
        for c in changes:
            scope = Scope(c.scope)
            target = _target(m, scope, c.target)
            if (scope.value, target, c.name) in seen:  # which one should win? neither
                err = ParamError(f"{c.name} is written twice in one change", name=c.name)
                problems.append(_problem(err, scope, target))
                continue
            seen.add((scope.value, target, c.name))
            try:
                d = resolve(scope, c.name)
                parsed.append((scope, target, d, c.name, _parse(d, c.name, c.value)))
            except ParamError as e:
                problems.append(_problem(e, scope, target, (lines or {}).get(c.name)))
        lists: dict[tuple[Scope, str], dict[str, Value]] = {}
        for scope, target, _d, name, value in parsed:
            lists.setdefault((scope, target), effective(m, scope, target))[name] = value
        for (scope, target), values in lists.items():
            for err in validate_values(scope, values):
                problems.append(_problem(err, scope, target, (lines or {}).get(err.name)))
        if problems:
            raise _rejected(problems)
        stale = _stale(m, store, changes, parsed)
        if stale:
            raise Conflict(
                {
                    "message": f"{stale[0].parameter} was written by {stale[0].by} since you "
                    f"read it (now {stale[0].current}): nothing applied",
                    "stale": [v.model_dump() for v in stale],
                }
            )
        stored: list[StoredChange] = []
        changed: list[tuple[Scope, str, ParamDef, str, Value]] = []
        for scope, target, d, name, value in parsed:
            key: Key = (scope.value, target, name)
            old = m.pending[key].value if key in m.pending else None
            if old is None:
                old = m.cfg.list_values(scope, target).get(name)
            if old is not None and old == value:
                continue  # the value it already has (a list re-imported): no change, no audit
            changed.append((scope, target, d, name, value))
            stored.append(StoredChange(scope.value, target, name, old, value, d.effect.value))
        if not changed:
            return ParameterWriteResult(changes=[])
        now: Values = []
        waiting: set[Key] = set()
        for scope, target, d, name, value in changed:
            key = (scope.value, target, name)
            if d.effect is Effect.NOW:
                now.append((scope.value, target, name, value))
            elif m.cfg.list_values(scope, target).get(name, d.default) == value:
                m.pending.pop(key, None)  # the value in force again: nothing waits (a revert)
            else:
                m.pending[key] = Pending(value, d.effect.value)
                waiting.add(key)
        if now:  # the running machine first: a write it cannot take is not stored
            m.link.call(ApplyValues(m.id, now))
            apply_values(m.cfg, now)
        versions = store.write(
            m.id,
            stored,
            [parameter_entry(m.id, actor.name, actor.session, c, comment) for c in stored],
        )
        return ParameterWriteResult(
            changes=[
                AppliedChange(
                    scope=c.scope,
                    target=c.target or None,
                    name=c.name,
                    old=c.old,
                    new=c.new,
                    effect=c.effect,
                    pending=(c.scope, c.target, c.name) in waiting,
                    version=version,
                )
                for c, version in zip(stored, versions, strict=True)
            ]
        )


def _stale(
    m: MachineProxy,
    store: Store,
    changes: list[ParameterChange],
    parsed: list[tuple[Scope, str, ParamDef, str, Value]],
) -> list[StaleValue]:
    """Changes based on a version older than the parameter's: someone wrote it meanwhile."""
    versions = store.versions(m.id)
    stale = []
    for c, (scope, target, _d, name, value) in zip(changes, parsed, strict=True):
        key = (scope.value, target, name)
        version = versions.get(key, 0)
        if c.base_version is None or c.base_version == version:
            continue
        rows = store.query("SELECT actor, time FROM audit_log WHERE seq = ?", (version,))
        current = m.pending[key].value if key in m.pending else None
        if current is None:
            current = m.cfg.list_values(scope, target).get(name)
        stale.append(
            StaleValue(
                parameter=name,
                target=target or None,
                yours=value,
                current=current,
                base_version=c.base_version,
                version=version,
                by=rows[0]["actor"] if rows else "?",
                time_unix=rows[0]["time"] if rows else None,
            )
        )
    return stale


def pending_values(m: MachineProxy, effects: set[str]) -> Values:
    """Pending values with these effects (call holding `m.lock`)."""
    return [(s, t, n, p.value) for (s, t, n), p in m.pending.items() if p.effect in effects]


def took_pending(m: MachineProxy, values: Values) -> None:
    """The running machine took these pending values: they are written now, and no longer
    pending unless a newer value is (call holding `m.lock`)."""
    apply_values(m.cfg, values)
    for scope, target, name, value in values:
        key = (scope, target, name)
        if key in m.pending and m.pending[key].value == value:
            del m.pending[key]


def _concrete_names(scope: Scope, kind: AxisKind, written: Mapping[str, Value]) -> list[str]:
    letter = _KIND_LETTER[kind]
    names: list[str] = []
    for d in registry():
        if d.scope is not scope or (scope is Scope.AXIS and letter not in d.axis_types):
            continue
        record = next((r for r in _RECORDS if d.name.startswith(r)), None)
        if record and "[" not in d.name[len(record) :]:
            stem, rest = record[: -len("[i].")], d.name[len(record) :]
            names += [f"{stem}[{i}].{rest}" for i in range(_RECORDS[record])]
        elif "[" not in d.name:
            names.append(d.name)
    return names + sorted(n for n in written if n not in set(names))


def read(
    m: MachineProxy, store: Store, scope: Scope, target: str | None, plant: bool = True
) -> list[ParameterValue]:
    """Every parameter of one list with value, default, unit, effect, pending value and
    version (the plant's sim.* only with `plant`)."""
    versions = store.versions(m.id)
    with m.lock:
        tgt = _target(m, scope, target)
        written = m.cfg.list_values(scope, tgt)
        kind = axis_kind_of(written) if scope is Scope.AXIS else AxisKind.LINEAR
        out = []
        for name in _concrete_names(scope, kind, written):
            if not plant and name.startswith(PLANT):
                continue
            d = resolve(scope, name)
            pending = m.pending.get((scope.value, tgt, name))
            key, indices = normalise_name(name)  # getriebe[2].kv: the gear record 2, M42
            gear = indices[0] + 1 if key.startswith("getriebe[]") else None
            lo, hi = value_range(d, name, written) if d.is_numeric else (None, None)
            out.append(
                ParameterValue(
                    scope=scope.value,
                    target=tgt or None,
                    name=name,
                    id=d.id,
                    value=written.get(name, d.default),
                    default=d.default,
                    set=name in written,
                    unit=d.raw_unit(kind),
                    effect=d.effect.value,
                    gear=gear,
                    pending=pending.value if pending else None,
                    title=d.title,
                    without_effect=d.without_effect,
                    min=lo,
                    max=hi,
                    eng_factor=d.display_unit(kind)[0] if d.is_numeric else None,
                    eng_unit=d.display_unit(kind)[1] if d.is_numeric else "",
                    version=versions.get((scope.value, tgt, name), 0),
                )
            )
        return out


def export_list(m: MachineProxy, scope: Scope, target: str | None, plant: bool = True) -> str:
    """The list in native format as the next restart would load it (pending included; the
    plant's sim.* only with `plant`)."""
    with m.lock:
        tgt = _target(m, scope, target)
        values = effective(m, scope, tgt)
    if not plant:
        values = {n: v for n, v in values.items() if not n.startswith(PLANT)}
    where = f" axis {tgt}" if tgt else ""
    title = f"Inbetrieb export: machine {m.id}, {scope.value} list{where}"
    return format_list(values, scope, [title])


def import_list(
    actor: Actor, m: MachineProxy, store: Store, scope: Scope, target: str | None, text: str
) -> ParameterWriteResult:
    """Parse a native list (errors with line numbers) and write its values as one change."""
    tgt = _target(m, scope, target)
    try:
        plist = parse_list(text, scope)
    except ParamListError as e:
        raise _rejected([_problem(p, scope, tgt) for p in e.errors]) from None
    if not plist.values:
        raise Invalid("the list holds no parameter values")
    lines = {ln.name: i for i, ln in enumerate(plist.lines, start=1) if ln.name}
    changes = [
        ParameterChange(scope=scope.value, target=tgt or None, name=n, value=v)
        for n, v in plist.values.items()
    ]
    return write(actor, m, store, changes, f"import {scope.value} list", lines)


def audit(store: Store, mid: str, limit: int) -> list[AuditEntry]:
    """The machine's parameter changes from the audit trail, oldest first."""
    return [
        AuditEntry(
            seq=seq,
            time_unix=when,
            machine=mid,
            actor=actor,
            scope=d["scope"],
            target=d["target"] or None,
            name=d["name"],
            old=d["old"],
            new=d["new"],
            effect=d["effect"],
            comment=d["comment"],
        )
        for seq, when, actor, d in store.parameter_history(mid, limit)
    ]
