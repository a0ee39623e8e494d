"""The commissioning report of a machine: its facts, who commissioned it and when (assistant
runs and parameter changes), every stored assistant run, the parameter differences against
the baseline, chosen traces, an audit excerpt and the sign-offs, gathered from the store for
backend/report/html.py. Sign-offs are stored here (table `sign_offs`) and audited.
"""

from __future__ import annotations

import asyncio
import time
from typing import Any

from api.report import AssistRun, SignOff, SignOffRequest
from backend.errors import Invalid
from backend.report import html
from backend.report.text import number
from backend.services.assist_runs import AssistRuns
from backend.services.audit import Audit, AuditFilter
from backend.services.audit_log import Entry
from backend.services.auth import Actor
from backend.services.machines import MachineProxy
from backend.services.store import Store
from backend.services.traces import TraceService
from backend.services.versions import Versions
from nc_sim.errors import NcUsageError
from nc_sim.params import ParamError, Scope, resolve

MAX_RUNS = 50  # the newest runs in a report
MAX_TRACES = 8  # traces chosen for one report
MAX_AUDIT = 100  # rows of the audit excerpt (newest)
EXCERPT_LEAVES_OUT = ("command",)  # jog renewals and MDI blocks would crowd out the rest
IMPORTED = "imported"  # the machine of a trace imported from CSV without a description


class Reports:
    """Builds reports and records sign-offs."""

    def __init__(
        self,
        store: Store,
        audit: Audit,
        runs: AssistRuns,
        traces: TraceService,
        versions: Versions | None = None,
    ) -> None:
        self.store, self.audit, self.runs, self.traces = store, audit, runs, traces
        self.versions = versions  # None: no baselines in this service ("no baseline set")

    # --- sign-off ---------------------------------------------------------------------------
    def sign_off(self, mid: str, actor: Actor, req: SignOffRequest) -> SignOff:
        """Record who signs the machine's commissioning off, with its audit row, in one
        transaction."""
        now = time.time()
        entry = Entry(
            actor.name,
            actor.session,
            "report",
            f"signed off by {req.name}" + (f" ({req.role})" if req.role else ""),
            mid,
            req.model_dump(),
            time=now,
        )

        def work(db: Any) -> int:
            cur = db.execute(
                "INSERT INTO sign_offs (machine, name, role, remark, user, time) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (mid, req.name, req.role, req.remark, actor.name, now),
            )
            self.store.append_audit(db, [entry])
            return int(cur.lastrowid)

        self.audit.flush()  # rows waiting to be written go first: the trail stays in order
        sid = self.store.transaction(work)
        return SignOff(
            id=sid,
            machine=mid,
            name=req.name,
            role=req.role,
            remark=req.remark,
            user=actor.name,
            time_unix=now,
        )

    def sign_offs(self, mid: str) -> list[SignOff]:
        """The machine's sign-offs, oldest first."""
        rows = self.store.query(
            "SELECT id, machine, name, role, remark, user, time FROM sign_offs "
            "WHERE machine = ? ORDER BY id",
            (mid,),
        )
        return [
            SignOff(
                id=r["id"],
                machine=r["machine"],
                name=r["name"],
                role=r["role"],
                remark=r["remark"],
                user=r["user"],
                time_unix=r["time"],
            )
            for r in rows
        ]

    # --- the report -------------------------------------------------------------------------
    async def build(self, m: MachineProxy, trace_ids: list[str], viewer: str) -> str:
        """The report of machine `m` as HTML, with the traces `trace_ids` (of this machine)
        plotted; 404 for an unknown trace, 422 for one of another machine or too many."""
        baseline = await self._baseline(m.id)
        data = await asyncio.to_thread(self._gather, m, trace_ids, viewer, baseline)
        return await asyncio.to_thread(html.render, data)

    async def _baseline(self, mid: str) -> list[html.BaselineRow] | None:
        if self.versions is None:
            return None
        diff = await self.versions.baseline_diff(mid)
        if diff is None:
            return None
        return [
            html.BaselineRow(
                d.target or d.scope,  # a channel or tool parameter: its list names it
                d.parameter,
                d.id,
                d.before,
                d.after,
                d.unit,
                _eng(d.before_eng, d.after_eng, d.eng_unit) if d.eng_unit != d.unit else "",
            )
            for d in diff
        ]

    def _gather(
        self,
        m: MachineProxy,
        trace_ids: list[str],
        viewer: str,
        baseline: list[html.BaselineRow] | None,
    ) -> html.ReportData:
        if len(trace_ids) > MAX_TRACES:
            raise Invalid(f"trace: at most {MAX_TRACES} traces in one report")
        traces = [self._trace(m.id, tid) for tid in dict.fromkeys(trace_ids)]
        runs = self.runs.runs(m.id, MAX_RUNS)
        total_runs = self.store.query(
            "SELECT count(*) AS n FROM assist_runs WHERE machine = ?", (m.id,)
        )[0]["n"]
        f = AuditFilter(machine=m.id, kinds_left_out=EXCERPT_LEAVES_OUT)
        page = self.audit.page(f, MAX_AUDIT)
        commands = self.audit.page(AuditFilter(machine=m.id, kind="command"), 0).total
        return html.ReportData(
            machine=html.MachineFacts(
                m.id,
                m.name,
                "demo lathe" if m.source == "demo" else "from parameter lists",
                [(a.name, a.kind.name.lower()) for a in m.cfg.axes],
            ),
            generated_unix=time.time(),
            generated_by=viewer,
            commissioners=self._commissioners(m.id),
            runs=runs,
            runs_left_out=max(0, total_runs - len(runs)),
            baseline=baseline,
            traces=traces,
            audit=page.rows,
            audit_total=page.total,
            audit_commands=commands,
            sign_offs=self.sign_offs(m.id),
            in_force=_in_force(m, runs),
        )

    def _trace(self, mid: str, tid: str) -> html.TracePlot:
        t = self.traces.get(tid)  # 404 when unknown
        d = t.detail
        if d.machine not in (mid, IMPORTED):  # an import without a machine may go anywhere
            raise Invalid(f"trace: {tid} was recorded on machine {d.machine}, not {mid}")
        if not d.channels or t.data.shape[-1] == 0:
            raise Invalid(f"trace: {tid} holds no samples")
        return html.TracePlot(
            id=d.id,
            name=d.name,
            notes=d.notes,
            created_unix=d.created_unix,
            trigger=f"{d.trigger} (forced)" if d.forced else d.trigger,
            t_s=t.times_s().tolist(),
            channels=[
                html.TraceChannel(c.name, c.unit, t.data[i].tolist())
                for i, c in enumerate(d.channels)
            ],
        )

    def _commissioners(self, mid: str) -> list[html.Commissioner]:
        """Who ran assistants or changed parameters on the machine, first to last."""
        seen: dict[str, list[float]] = {}  # user -> [runs, changes, first, last]
        rows = self.store.query(
            "SELECT user, count(*) AS n, min(time) AS first, max(time) AS last FROM assist_runs "
            "WHERE machine = ? GROUP BY user",
            (mid,),
        )
        for r in rows:
            seen[r["user"]] = [r["n"], 0, r["first"], r["last"]]
        self.audit.flush()
        rows = self.store.query(
            "SELECT actor, count(*) AS n, min(time) AS first, max(time) AS last FROM audit_log "
            "WHERE machine = ? AND kind = 'parameter' AND outcome = 'ok' GROUP BY actor",
            (mid,),
        )
        for r in rows:
            s = seen.setdefault(r["actor"], [0, 0, r["first"], r["last"]])
            s[1], s[2], s[3] = r["n"], min(s[2], r["first"]), max(s[3], r["last"])
        out = [html.Commissioner(u, int(v[0]), int(v[1]), v[2], v[3]) for u, v in seen.items()]
        return sorted(out, key=lambda c: c.first_unix)


def _eng(before: float | None, after: float | None, unit: str) -> str:
    """Baseline → now in engineering units ('20 → 25 1/s'), '' when not numbers."""
    if before is None or after is None:
        return ""
    return f"{number(before)} → {number(after)} {unit}".strip()


def _in_force(m: MachineProxy, runs: list[AssistRun]) -> dict[tuple[str, str], object]:
    """The list value now of every parameter the runs proposed (its default where unset)."""
    out: dict[tuple[str, str], object] = {}
    for run in runs:
        for c in run.result.changes:
            scope = Scope.CHANNEL if c.target == "channel" else Scope.AXIS
            try:
                values = m.cfg.list_values(scope, c.target)
                out[(c.target, c.parameter)] = values.get(
                    c.parameter, resolve(scope, c.parameter).default
                )
            except (NcUsageError, ParamError):  # an axis or parameter the machine lost
                continue
    return out
