"""Parameter versions: named snapshots of a machine's lists (channel, every axis, tools) as the
next restart would load them, one of them the machine's baseline; differences between any
two states (a version, the live parameters, the manuals' defaults) and rollback to a version.

A version holds the written values only: a value not written is the manual's default, so a
difference compares `value if written else default`. Rollback is an ordinary parameter write
(`parameters.write`: validated all together, pending at reset/restart as any write, audited
row by row), which the HMI puts on trial (Keep / Revert) as any other write.
"""

from __future__ import annotations

import asyncio
import json
import sqlite3
import time
from collections.abc import Iterator
from dataclasses import dataclass, replace

from api.parameters import ParameterChange, ParameterWriteResult
from api.versions import ParamDiff, VersionInfo
from backend.errors import ApiError, Conflict, not_found
from backend.services import audit_log
from backend.services import parameters as params
from backend.services.auth import Actor
from backend.services.machines import MachineProxy, MachineService
from backend.services.store import Row, Store
from nc_sim.params import ParamDef, ParamError, Scope, Value, resolve
from nc_sim.params.listfile import axis_kind_of
from nc_sim.units import AxisKind

MAX_VERSIONS = 1000  # per machine: a script taking one per minute is told, not the disk filled
LIVE, DEFAULTS, BASELINE = "live", "defaults", "baseline"
STATE_PATTERN = r"^(live|defaults|baseline|[0-9]{1,15})$"

ListKey = tuple[str, str]  # scope, target ('' for channel and tool)
Lists = dict[ListKey, dict[str, Value]]
_COLUMNS = "id, machine, name, note, created, created_by, baseline, lists"


@dataclass(frozen=True)
class State:
    """One side of a difference: its values per list and what it is, in words."""

    lists: Lists
    label: str


def _info(r: Row) -> VersionInfo:
    lists = json.loads(str(r["lists"]))
    return VersionInfo(
        id=int(str(r["id"])),
        machine=str(r["machine"]),
        name=str(r["name"]),
        note=str(r["note"]),
        created_unix=float(str(r["created"])),
        created_by=str(r["created_by"]),
        baseline=bool(r["baseline"]),
        values=len(lists),
    )


def _lists(text: str) -> Lists:
    out: Lists = {}
    for scope, target, name, value in json.loads(text):
        out.setdefault((scope, target), {})[name] = value
    return out


def _list_keys(m: MachineProxy) -> list[ListKey]:
    """The machine's lists in the parameter page's order: axes, channel, tools."""
    return [
        *((Scope.AXIS.value, ax.name) for ax in m.cfg.axes),
        (Scope.CHANNEL.value, ""),
        (Scope.TOOL.value, ""),
    ]


def live_lists(m: MachineProxy) -> Lists:
    """Every list as the next restart would load it (pending values included)."""
    with m.lock:
        return {(s, t): params.effective(m, Scope(s), t) for s, t in _list_keys(m)}


def _definition(scope: str, name: str) -> ParamDef | None:
    try:
        return resolve(Scope(scope), name)
    except ParamError:
        return None  # a name the registry no longer knows: not compared


def _compared(m: MachineProxy, a: Lists, b: Lists) -> Iterator[tuple[ListKey, ParamDef, str]]:
    """(list, definition, name) of every parameter written on either side."""
    for key in _list_keys(m):
        names = set(a.get(key, {})) | set(b.get(key, {}))
        for name in sorted(names):
            d = _definition(key[0], name)
            if d is not None:
                yield key, d, name


def _value(d: ParamDef, values: dict[str, Value], name: str) -> Value:
    """The value in force: written, else the default; an enum's symbol as its code, so the
    default `ACHSTYP_TRANSLATOR` and a written 1 are the same value."""
    v = values.get(name, d.default)
    return d.symbols.get(v, v) if isinstance(v, str) and d.symbols else v


def _eng(d: ParamDef, v: Value | None, kind: AxisKind) -> float | None:
    if not d.is_numeric or d.symbols or isinstance(v, str) or v is None:
        return None
    return float(v) * d.display_unit(kind)[0]


def diff(m: MachineProxy, a: Lists, b: Lists) -> list[ParamDiff]:
    """Every parameter whose value (written, else the default) differs from `a` to `b`."""
    kinds = {ax.name: axis_kind_of(ax.values) for ax in m.cfg.axes}
    out = []
    for (scope, target), d, name in _compared(m, a, b):
        before = _value(d, a.get((scope, target), {}), name)
        after = _value(d, b.get((scope, target), {}), name)
        if before == after:
            continue
        kind = kinds.get(target, AxisKind.LINEAR)
        eng_unit = d.display_unit(kind)[1] if d.is_numeric else ""
        out.append(
            ParamDiff(
                scope=scope,
                target=target or None,
                parameter=name,
                id=d.id,
                title=d.title,
                before=before,
                after=after,
                unit=d.raw_unit(kind),
                before_eng=_eng(d, before, kind),
                after_eng=_eng(d, after, kind),
                eng_unit=eng_unit,
                effect=d.effect.value,
            )
        )
    return out


def _taken(name: str, mid: str) -> ApiError:
    return Conflict(f"machine {mid} already has a version named '{name}': choose another name")


class Versions:
    """The versions of every machine in the store's `param_versions` table."""

    def __init__(self, store: Store, machines: MachineService) -> None:
        self.store = store
        self.machines = machines

    # --- reading -------------------------------------------------------------------------------
    def of(self, mid: str) -> list[VersionInfo]:
        """The machine's versions, newest first."""
        self.machines.get(mid)  # 404 for an unknown machine
        rows = self.store.query(
            f"SELECT {_COLUMNS} FROM param_versions WHERE machine = ? ORDER BY id DESC", (mid,)
        )
        return [_info(r) for r in rows]

    def _row(self, mid: str, vid: int) -> Row:
        rows = self.store.query(
            f"SELECT {_COLUMNS} FROM param_versions WHERE machine = ? AND id = ?", (mid, vid)
        )
        if not rows:
            raise not_found(f"version {vid} of machine {mid}")
        return rows[0]

    def _baseline_row(self, mid: str) -> Row | None:
        rows = self.store.query(
            f"SELECT {_COLUMNS} FROM param_versions WHERE machine = ? AND baseline = 1", (mid,)
        )
        return rows[0] if rows else None

    def state(self, m: MachineProxy, which: str) -> State:
        """A side of a difference: 'live', 'defaults', 'baseline' or a version's id."""
        if which == LIVE:
            return State(live_lists(m), "live parameters")
        if which == DEFAULTS:
            return State({}, "the manuals' defaults")
        row = self._baseline_row(m.id) if which == BASELINE else self._row(m.id, int(which))
        if row is None:
            raise not_found(f"a baseline of machine {m.id} (set one first)")
        what = "baseline" if row["baseline"] else "version"
        return State(_lists(str(row["lists"])), f"{what} '{row['name']}'")

    def compare(self, mid: str, a: str, b: str) -> tuple[State, State, list[ParamDiff]]:
        """The differences from state `a` to state `b`."""
        m = self.machines.get(mid)
        sa, sb = self.state(m, a), self.state(m, b)
        return sa, sb, diff(m, sa.lists, sb.lists)

    def baseline_diff_now(self, mid: str) -> list[ParamDiff] | None:
        """The live parameters against the baseline; None without a baseline."""
        if self._baseline_row(mid) is None:
            self.machines.get(mid)  # an unknown machine is still 404
            return None
        return self.compare(mid, BASELINE, LIVE)[2]

    async def baseline_diff(self, mid: str) -> list[ParamDiff] | None:
        """The live parameters against the baseline (None without one), off the event loop
        (the store's lock and the machine's may be held by a request)."""
        return await asyncio.to_thread(self.baseline_diff_now, mid)

    # --- changing (each audited in the same transaction) ----------------------------------------
    def take(self, actor: Actor, mid: str, name: str, note: str, baseline: bool) -> VersionInfo:
        """Store the live parameters as a version (and as the baseline)."""
        m = self.machines.get(mid)
        rows = [[s, t, n, v] for (s, t), values in live_lists(m).items() for n, v in values.items()]
        now = time.time()
        what = "baseline" if baseline else "version"
        entry = audit_log.Entry(
            actor.name,
            actor.session,
            "version",
            f"took {what} '{name}' ({len(rows)} written values)",
            mid,
            detail={"name": name, "note": note, "baseline": baseline, "values": len(rows)},
            time=now,
        )

        def work(db: sqlite3.Connection) -> int:
            count = db.execute(
                "SELECT count(*) AS n FROM param_versions WHERE machine = ?", (mid,)
            ).fetchone()["n"]
            if count >= MAX_VERSIONS:
                raise Conflict(
                    f"machine {mid} has {count} versions, the most it keeps: delete old ones first"
                )
            if baseline:
                db.execute("UPDATE param_versions SET baseline = 0 WHERE machine = ?", (mid,))
            cur = db.execute(
                "INSERT INTO param_versions (machine, name, note, created, created_by, "
                "baseline, lists) VALUES (?, ?, ?, ?, ?, ?, ?)",
                (mid, name, note, now, actor.name, int(baseline), json.dumps(rows)),
            )
            vid = int(cur.lastrowid or 0)
            self.store.append_audit(db, [replace(entry, detail={**entry.detail, "id": vid})])
            return vid

        try:
            vid = self.store.transaction(work)
        except sqlite3.IntegrityError:
            raise _taken(name, mid) from None
        return _info(self._row(mid, vid))

    def set_baseline(self, actor: Actor, mid: str, vid: int) -> VersionInfo:
        """Make a version the machine's baseline (the previous one stays a plain version)."""
        self.machines.get(mid)
        row = self._row(mid, vid)
        entry = audit_log.Entry(
            actor.name,
            actor.session,
            "version",
            f"set baseline: version '{row['name']}'",
            mid,
            detail={"id": vid, "name": row["name"]},
        )

        def work(db: sqlite3.Connection) -> None:
            db.execute("UPDATE param_versions SET baseline = 0 WHERE machine = ?", (mid,))
            db.execute("UPDATE param_versions SET baseline = 1 WHERE id = ?", (vid,))
            self.store.append_audit(db, [entry])

        self.store.transaction(work)
        return _info(self._row(mid, vid))

    def delete(self, actor: Actor, mid: str, vid: int) -> None:
        """Delete a version; the baseline only after another took its place."""
        self.machines.get(mid)
        row = self._row(mid, vid)
        if row["baseline"]:
            raise Conflict(
                f"version '{row['name']}' is the baseline of {mid}: make another "
                "version the baseline first"
            )
        entry = audit_log.Entry(
            actor.name,
            actor.session,
            "version",
            f"deleted version '{row['name']}'",
            mid,
            detail={"id": vid, "name": row["name"]},
        )

        def work(db: sqlite3.Connection) -> None:
            db.execute("DELETE FROM param_versions WHERE id = ?", (vid,))
            self.store.append_audit(db, [entry])

        self.store.transaction(work)

    def rollback(self, actor: Actor, mid: str, vid: int, comment: str) -> ParameterWriteResult:
        """Write every value that differs from the version (a value the version did not
        write goes back to its default) as one parameter write, then audit the rollback."""
        m = self.machines.get(mid)
        row = self._row(mid, vid)
        changes = [
            ParameterChange(scope=c.scope, target=c.target, name=c.parameter, value=c.after)
            for c in diff(m, live_lists(m), _lists(str(row["lists"])))
            if c.after is not None
        ]
        why = f"rollback to version '{row['name']}'" + (f": {comment}" if comment else "")
        result = (
            params.write(actor, m, self.store, changes, why)
            if changes
            else ParameterWriteResult(changes=[])
        )
        n = len(result.changes)
        entry = audit_log.Entry(
            actor.name,
            actor.session,
            "version",
            f"rolled back to version '{row['name']}' ({n} value{'' if n == 1 else 's'} changed)",
            mid,
            detail={
                "id": vid,
                "name": row["name"],
                "changed": len(result.changes),
                "comment": comment,
            },
        )
        self.store.transaction(lambda db: self.store.append_audit(db, [entry]))
        return result
