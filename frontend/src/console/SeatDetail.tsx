// One seat for the instructor and the debrief: the exercise's checks (measured figure, first
// pass), hints taken, injected faults (remove one), snapshots (take, restore), the seat's
// traces and what happened on its machine (its history: job errors with their cause,
// commands, parameters, faults, hints, freezes and messages) and its replay (the signals and
// that history on the seat's clock, played back). An ended class keeps all but the
// machine: its checks' figures and faults as they stood at the end.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { ClassInfo, HistoryPage, Refusal, SeatDetail as Detail, SeatLink, SnapshotInfo, TraceInfo } from "../api/types";
import { newLink } from "../state/classes";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { Replay } from "./Replay";
import { clock } from "./SeatTile";
import { detailSeat } from "./uiState";

const REFRESH_MS = 3000; // a running seat's checks and faults change as the student works
const HISTORY_ROWS = 200;
const time = (unix: number) => new Date(unix * 1000).toLocaleTimeString();

interface Loaded {
  detail: Detail;
  snapshots: SnapshotInfo[];
  traces: TraceInfo[];
  history: HistoryPage;
}

export function SeatDetail(props: { c: ClassInfo; n: number }) {
  const { c, n } = props;
  const running = c.ended_unix === null;
  const seat = c.seats.find((s) => s.n === n);
  const mid = seat?.machine ?? "";
  const [data, setData] = useState<Loaded | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [link, setLink] = useState<SeatLink | null>(null);
  const [tick, setTick] = useState(0);
  const fail = (e: unknown) => setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
  useEffect(() => {
    if (!seat) return; // another class was just opened: its seats are not this one's
    let live = true;
    const load = async () => {
      const [detail, traces, history, snapshots] = await Promise.all([
        http.get<Detail>(`/api/classes/${c.id}/seats/${n}`),
        http.get<TraceInfo[]>(`/api/traces?machine=${encodeURIComponent(mid)}`),
        http.get<HistoryPage>(`/api/classes/${c.id}/seats/${n}/history?limit=${HISTORY_ROWS}`),
        running ? http.get<SnapshotInfo[]>(`/api/machines/${mid}/snapshots`) : Promise.resolve([]),
      ]);
      if (live) {
        setData({ detail, traces, history, snapshots });
        setRefusal(null); // the service answers again (after a restart, say)
      }
    };
    load().catch(fail);
    const timer = running ? setInterval(() => void load().catch(fail), REFRESH_MS) : undefined;
    return () => {
      live = false;
      clearInterval(timer);
    };
  }, [c.id, n, running, mid, tick]);
  const then = (p: Promise<unknown>) => void p.then(() => setTick((t) => t + 1), fail);
  const d = data?.detail;
  if (!seat) return null;
  return (
    <Panel id="seat-detail" title={`Seat ${n}: ${seat?.student ?? ""}${running ? "" : " (debrief)"}`}
      actions={<button type="button" class="secondary" data-testid="detail-close" onClick={() => (detailSeat.value = null)}>Close</button>}>
      <RefusalLine refusal={refusal} id="detail-refusal" />
      {d ? (
        <p class="hint">
          {mid} · login {d.info.user} · {c.exercises.length > 1 ? "in this exercise: " : ""}seat time {clock(d.info.seat_time_s)} · progress {Math.round(d.info.progress * 100)} % · score{" "}
          <b>{fmt(d.info.score, 1)}</b> · hints taken {d.info.hints_taken}
          {running ? (
            <>
              {" "}·{" "}
              <button type="button" class="link" title="a new link: the seat's old link and whoever is logged in with it are logged out"
                onClick={() => confirm(`A new login link for seat ${n}: whoever is logged in on it now is logged out. Go on?`) && void newLink(c.id, n).then(setLink, fail)}>
                new login link
              </button>
            </>
          ) : null}
        </p>
      ) : <p class="hint">loading…</p>}
      {link ? <p class="once-note">Shown this once: <input readOnly aria-label="login link" class="mono link-url" value={link.url} /></p> : null}
      {d && c.exercises.length > 1 ? (
        <p data-testid="detail-stage">
          Exercise <b>{d.info.stage + 1}</b> of {c.exercises.length} (<code>{c.exercises[d.info.stage]}</code>) · over the plan{" "}
          <b>{fmt(d.info.total_score, 1)}</b> points
        </p>
      ) : null}
      {d && Object.keys(d.values).length ? (
        <p class="hint" data-testid="detail-values">
          This seat's own numbers: {Object.entries(d.values).map(([k, v]) => `${k} = ${fmt(v, 4)}`).join(" · ")}
        </p>
      ) : null}
      {d?.info.done.length ? (
        <table class="dense" data-testid="detail-done">
          <thead><tr><th>exercise done</th><th class="num">score</th><th class="num">checks</th><th class="num">hints</th><th class="num">seat time</th><th>moved on</th></tr></thead>
          <tbody>
            {d.info.done.map((r) => (
              <tr key={r.exercise}>
                <td>{r.title}</td>
                <td class="num">{fmt(r.score, 1)} of {fmt(r.max_points, 0)}</td>
                <td class="num">{r.checks.filter((k) => k.first_passed_s !== null).length} of {r.checks.length}</td>
                <td class="num">{r.hints_taken}</td>
                <td class="num">{clock(r.seat_time_s)}</td>
                <td>by {r.moved_on_by} at {time(r.moved_on_unix)}</td>
              </tr>
            ))}
          </tbody>
        </table>
      ) : null}
      <div class="detail-cols">
        <section>
          <h3>Checks{c.exercises.length > 1 && d ? ` (exercise ${d.info.stage + 1})` : ""}</h3>
          <table class="dense" data-testid="detail-checks">
            <thead><tr><th>check</th><th>passed</th>{running ? <th>holds now</th> : null}
              <th>{running ? "measured" : "last measured, at the end"}</th><th class="num">points</th></tr></thead>
            <tbody>
              {d?.checks.map((k) => (
                <tr key={k.id} data-testid={`detail-check-${k.id}`}>
                  <td>{k.text}</td>
                  {/* a check counts once passed: when, in seat time */}
                  <td class={k.first_passed_s !== null ? "ok" : "bad"}>{k.first_passed_s !== null ? `yes, at ${clock(k.first_passed_s)}` : "no"}</td>
                  {running ? <td class={k.passed ? "ok" : ""}>{k.passed ? "yes" : "no"}</td> : null}
                  <td>{k.detail}</td>
                  <td class="num" data-testid="detail-check-points">{fmt(k.earned, 1)} of {fmt(k.points, 0)}</td>
                </tr>
              ))}
            </tbody>
          </table>
          <h3>Hints</h3>
          <ul class="plain">
            {d?.hints.map((h) => (
              <li key={h.n}>{h.n}. {h.text ? <>taken (−{fmt(h.cost, 0)} pt): {h.text}</> : <span class="hint">not taken ({fmt(h.cost, 0)} pt)</span>}</li>
            ))}
          </ul>
          <h3>Faults</h3>
          <ul class="plain" data-testid="detail-faults">
            {d?.faults.map((f) => (
              <li key={f.id}>
                <b>{f.text}</b>{" "}
                <span class="hint">
                  {f.active ? `active since machine t = ${fmt(f.active_since_s, 1)} s` : running ? "armed" : "armed, never took effect"}
                  {f.injected_s > 0 ? ` · injected at machine t = ${fmt(f.injected_s, 1)} s` : " · since the machine's start (the exercise's, or kept across a power-on)"}
                </span>{" "}
                {running ? (
                  <button type="button" class="link" data-testid={`fault-remove-${f.id}`} onClick={() => then(http.del(`/api/machines/${mid}/faults/${f.id}`))}>remove</button>
                ) : null}
              </li>
            ))}
            {d && !d.faults.length ? <li class="hint">none</li> : null}
          </ul>
          {running ? (
            <>
              <h3>Snapshots</h3>
              <ul class="plain" data-testid="detail-snapshots">
                {data?.snapshots.map((s) => (
                  <li key={s.id}>
                    {s.id}: machine t = {fmt(s.t_s, 1)} s {s.label ? `"${s.label}"` : ""} <span class="hint">by {s.by} at {time(s.created_unix)}</span>{" "}
                    <button type="button" class="link" data-testid={`snapshot-restore-${s.id}`}
                      onClick={() => confirm(`Restore seat ${n}'s machine to ${fmt(s.t_s, 1)} s? What the student did since is lost.`) && then(http.post(`/api/machines/${mid}/snapshots/${s.id}/restore`, {}))}>
                      restore
                    </button>
                  </li>
                ))}
                {data && !data.snapshots.length ? <li class="hint">none</li> : null}
              </ul>
              <button type="button" class="secondary" data-testid="snapshot-take" onClick={() => then(http.post(`/api/machines/${mid}/snapshots`, { label: "" }))}>
                Take snapshot
              </button>{" "}
              <button type="button" class="secondary" data-testid="seat-reset" title="its lists, state and faults as when the class began; its record (checks, hints, seat time) stays"
                onClick={() => confirm(`Put seat ${n}'s machine back to the exercise's start? What the student changed since is lost; what they earned stays.`) && then(http.post(`/api/classes/${c.id}/seats/${n}/reset`, {}))}>
                Reset to the exercise's start
              </button>
            </>
          ) : null}
        </section>
        <section>
          <h3>Traces</h3>
          <ul class="plain" data-testid="detail-traces">
            {data?.traces.map((t) => (
              <li key={t.id}>
                <a href={`/api/traces/${t.id}/csv`}>{t.name || t.id}</a> <span class="hint">{time(t.created_unix)} · {t.trigger}</span>
              </li>
            ))}
            {data && !data.traces.length ? <li class="hint">none</li> : null}
          </ul>
          <h3>What happened ({data?.history.total ?? 0})</h3>
          <table class="dense" data-testid="detail-history">
            <tbody>
              {data?.history.rows.map((r) => (
                <tr key={r.id} class={r.severity === "error" ? "bad" : ""} data-kind={r.kind}>
                  <td class="num">{time(r.time_unix)}</td>
                  <td>{r.actor || "NC"}</td>
                  <td>
                    {r.code !== null ? <b>{r.code} </b> : null}
                    {r.text}
                    {r.cause ? <div class="hint">{r.cause}</div> : null}
                  </td>
                  <td class={r.outcome && r.outcome !== "ok" ? "bad" : ""}>{r.outcome}</td>
                </tr>
              ))}
            </tbody>
          </table>
        </section>
      </div>
      {d ? <Replay c={c} n={n} stage={d.info.stage} /> : null}
    </Panel>
  );
}
