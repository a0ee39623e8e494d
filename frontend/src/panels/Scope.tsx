// The Scope workspace: setup and library beside the capture on screen (or the rolling
// window), with cursors, measurements, an overlaid stored trace and the parameter differences.
import { useEffect, useMemo, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { TraceCompare, TraceDetail } from "../api/types";
import {
  followNewest,
  loadRoll,
  loadTrace,
  overlayId,
  pollScope,
  refreshLibrary,
  SCOPE_PERIOD_MS,
  scopeStatus,
  shownId,
  type LoadedTrace,
  type RollData,
} from "../state/scope";
import { catalogue } from "../state/telemetry";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { CommandStrip } from "./CommandStrip";
import { CaptureChart, type Cursors, type Overlay, type Series } from "./CaptureChart";
import { Measurements } from "./Measurements";
import { ScopeSetup } from "./ScopeSetup";
import { TraceLibrary, TraceLinks, when } from "./TraceLibrary";

/** Index of the sample nearest to time v. */
function nearest(t: Float64Array, v: number): number {
  let lo = 0;
  let hi = t.length - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (t[mid] < v) lo = mid;
    else hi = mid;
  }
  return Math.abs(t[lo] - v) <= Math.abs(t[hi] - v) ? lo : hi;
}

function CursorTable(props: { trace: LoadedTrace; cursors: Cursors }) {
  const { trace, cursors } = props;
  const [a, b] = cursors;
  const at = (v: number | null) => (v === null ? null : nearest(trace.t, v));
  const ia = at(a);
  const ib = at(b);
  const ta = ia === null ? null : trace.t[ia];
  const tb = ib === null ? null : trace.t[ib];
  return (
    <table class="cursor-table" data-testid="cursor-table">
      <thead>
        <tr>
          <th />
          <th>A</th>
          <th>B</th>
          <th>Δ = B − A</th>
        </tr>
      </thead>
      <tbody>
        <tr>
          <th>t [s]</th>
          <td data-testid="cursor-a-t">{fmt(ta, 4)}</td>
          <td data-testid="cursor-b-t">{fmt(tb, 4)}</td>
          <td data-testid="cursor-dt">{ta !== null && tb !== null ? `${fmt((tb - ta) * 1000, 1)} ms` : "—"}</td>
        </tr>
        {trace.detail.channels.map((c) => {
          const y = trace.channels.get(c.name)!;
          const ya = ia === null ? null : y[ia];
          const yb = ib === null ? null : y[ib];
          return (
            <tr key={c.name}>
              <th>{c.name}{c.unit ? ` [${c.unit}]` : ""}</th>
              <td>{fmt(ya, 4)}</td>
              <td>{fmt(yb, 4)}</td>
              <td data-testid={`cursor-dy-${c.name}`}>{ya !== null && yb !== null ? fmt(yb - ya, 4) : "—"}</td>
            </tr>
          );
        })}
      </tbody>
    </table>
  );
}

function SaveForm(props: { id: string; onSaved: () => void }) {
  const [name, setName] = useState("");
  const [notes, setNotes] = useState("");
  const [error, setError] = useState("");
  return (
    <form class="save-form" onSubmit={(e) => {
      e.preventDefault();
      http.post(`/api/traces/${props.id}/save`, { name, notes })
        .then(() => { setError(""); props.onSaved(); })
        .catch((err) => setError(err instanceof ApiError ? err.refusal.message : String(err)));
    }}>
      <input placeholder="name" value={name} data-testid="save-name" onInput={(e) => setName((e.target as HTMLInputElement).value)} />
      <input placeholder="notes (kv, what changed …)" value={notes} class="wide" onInput={(e) => setNotes((e.target as HTMLInputElement).value)} />
      <button type="submit" data-testid="save-trace">Save to library</button>
      {error ? <span class="refusal">{error}</span> : null}
    </form>
  );
}

/** The events in the record and the parameters as they were, below the chart. */
function RecordFacts(props: { detail: TraceDetail }) {
  const d = props.detail;
  const ref = d.trigger_cycle ?? d.first_cycle;
  return (
    <div class="record-facts">
      <details data-testid="capture-events">
        <summary>Events in the record ({d.events.length})</summary>
        <table class="param-diff">
          <tbody>
            {d.events.map((e) => (
              <tr key={`${e.cycle}:${e.code}:${e.axis}`} class={e.error ? "error" : ""}>
                <td>{fmt((e.cycle - ref) * d.cycle_s, 3)} s</td>
                <td>{e.code}</td>
                <td>{e.axis}</td>
                <td>{e.message}</td>
              </tr>
            ))}
          </tbody>
        </table>
      </details>
      <details data-testid="capture-params">
        <summary>Parameters at capture time: {d.params_changed} differ from the defaults</summary>
        <table class="param-diff">
          <thead>
            <tr><th>list</th><th>parameter</th><th>value</th><th>default</th></tr>
          </thead>
          <tbody>
            {d.params.map((p) => (
              <tr key={`${p.scope}${p.target}${p.name}`}>
                <td>{p.target || p.scope}</td>
                <td>{p.name}</td>
                <td>{String(p.value)}</td>
                <td>{p.default === null ? "—" : String(p.default)}</td>
              </tr>
            ))}
          </tbody>
        </table>
      </details>
    </div>
  );
}

function CaptureView() {
  const [trace, setTrace] = useState<LoadedTrace | null>(null);
  const [overlay, setOverlay] = useState<LoadedTrace | null>(null);
  const [cursors, setCursors] = useState<Cursors>([null, null]);
  const [range, setRange] = useState<[number, number] | null>(null);
  const [compare, setCompare] = useState<TraceCompare | null>(null);
  const [error, setError] = useState("");
  const st = scopeStatus.value;
  const recent = st?.captures ?? [];

  useEffect(() => {
    const id = shownId.value;
    if (!id) return setTrace(null);
    loadTrace(id)
      .then((t) => {
        if (shownId.peek() !== id) return; // another was chosen meanwhile (another machine)
        setTrace(t);
        setCursors([null, null]);
        setRange(null);
        setError("");
      })
      .catch((e) => setError(String(e)));
  }, [shownId.value]);

  useEffect(() => {
    if (!overlayId.value) return setOverlay(null);
    loadTrace(overlayId.value).then(setOverlay).catch((e) => setError(String(e)));
  }, [overlayId.value]);

  useEffect(() => {
    if (!trace || !overlay) return setCompare(null);
    http.get<TraceCompare>(`/api/traces/compare?a=${overlay.detail.id}&b=${trace.detail.id}`).then(setCompare).catch(() => setCompare(null));
  }, [trace?.detail.id, overlay?.detail.id]);

  const series: Series[] = trace
    ? trace.detail.channels.map((c) => ({ name: c.name, unit: c.unit, kind: c.kind, data: trace.channels.get(c.name)! }))
    : [];
  // one object per overlay: the chart rebuilds when it changes identity
  const ov = useMemo<Overlay | null>(
    () => (overlay && trace ? { label: overlay.detail.name || "overlay", t: overlay.t, channels: overlay.channels } : null),
    [overlay, trace],
  );
  const d = trace?.detail;
  // a drive-rate capture: its samples are drive steps (their signals are `<axis>.drive.*`)
  const drive = d?.channels.some((c) => c.name.split(".")[1] === "drive") ?? false;

  return (
    <Panel title="Capture" id="capture"
      actions={
        <span class="capture-pick">
          <label>
            <input type="checkbox" checked={followNewest.value} onChange={(e) => (followNewest.value = (e.target as HTMLInputElement).checked)} />
            show each new capture
          </label>
          <select value={recent.some((c) => c.id === shownId.value) ? shownId.value : ""} aria-label="recent captures" data-testid="recent-captures"
            onChange={(e) => (shownId.value = (e.target as HTMLSelectElement).value)}>
            <option value="">recent captures ({recent.length})</option>
            {recent.map((c) => (
              <option key={c.id} value={c.id}>{when(c.created_unix)} · {c.trigger}</option>
            ))}
          </select>
        </span>
      }>
      {error ? <p class="refusal">{error}</p> : null}
      {trace && d ? (
        <div class="capture" data-testid="capture-view" data-trace={d.id} data-drive={drive ? "yes" : undefined}>
          <div class="capture-head">
            <b data-testid="capture-trigger">{d.name || d.trigger || "capture"}</b>
            <span>
              {d.machine_name} · {when(d.created_unix)} · trigger at {drive ? "drive step" : "cycle"} {d.trigger_cycle ?? "—"}
              {d.forced ? " (forced)" : ""} · {d.count} {drive ? "samples" : "cycles"} of{" "}
              {d.cycle_s < 0.001 ? `${fmt(d.cycle_s * 1e6, 0)} µs` : `${fmt(d.cycle_s * 1000, 2)} ms`} ·{" "}
              <span data-testid="capture-pre">{fmt(((d.trigger_cycle ?? d.first_cycle) - d.first_cycle) * d.cycle_s, 3)} s</span> before
            </span>
            <TraceLinks id={d.id} />
          </div>
          {!d.stored ? <SaveForm id={d.id} onSaved={() => void refreshLibrary().then(() => loadTrace(d.id).then(setTrace))} /> : null}
          <CaptureChart t={trace.t} series={series} overlay={ov} trigger={d.trigger_cycle !== null} cursors={cursors}
            onCursors={setCursors} onRange={setRange} testid="capture-chart" />
          <div class="capture-below">
            <CursorTable trace={trace} cursors={cursors} />
            <Measurements detail={d} cursors={cursors} range={range} compare={overlay?.detail ?? null} />
          </div>
          <RecordFacts detail={d} />
          {overlay ? (
            <div class="compare" data-testid="compare">
              Overlay: <b>{overlay.detail.name || overlay.detail.trigger}</b> (dashed){" "}
              <button type="button" class="link" onClick={() => (overlayId.value = "")}>remove</button>
              {compare ? (
                compare.params.length ? (
                  <table class="param-diff">
                    <thead>
                      <tr><th>parameter</th><th>overlay</th><th>shown</th></tr>
                    </thead>
                    <tbody>
                      {compare.params.map((p) => (
                        <tr key={`${p.scope}${p.target}${p.name}`}>
                          <td>{p.target ? `${p.target} ` : ""}{p.name}</td>
                          {/* null only for an import: it has no parameter snapshot */}
                          <td>{p.a ?? "not recorded"}</td>
                          <td>{p.b ?? "not recorded"}</td>
                        </tr>
                      ))}
                    </tbody>
                  </table>
                ) : (
                  <span class="hint"> · same parameters</span>
                )
              ) : null}
            </div>
          ) : null}
        </div>
      ) : (
        <p class="hint">No capture on screen. Arm the scope, or pick a recent capture or a stored trace.</p>
      )}
    </Panel>
  );
}

function RollView() {
  const [data, setData] = useState<RollData | null>(null);
  const [cursors, setCursors] = useState<Cursors>([null, null]);
  useEffect(() => {
    let alive = true;
    const tick = () => loadRoll(4000).then((r) => alive && r && setData(r));
    const id = setInterval(tick, SCOPE_PERIOD_MS);
    void tick();
    return () => {
      alive = false;
      clearInterval(id);
    };
  }, []);
  if (!data) return null;
  const info = (n: string) => catalogue.value.find((s) => s.name === n);
  const series: Series[] = [...data.channels].map(([name, y]) => ({
    name,
    unit: info(name)?.unit ?? "",
    kind: info(name)?.kind ?? "float",
    data: y,
  }));
  return (
    <Panel title="Roll" id="roll">
      <p class="hint" data-testid="roll-info" data-last-cycle={data.lastCycle} data-span-s={data.t.length ? -data.t[0] : 0}>
        newest cycle {data.lastCycle} · {fmt(data.t.length ? -data.t[0] : 0, 3)} s shown
        {data.stride > 1 ? ` · every ${data.stride}th cycle drawn` : ""}
      </p>
      <CaptureChart t={data.t} series={series} overlay={null} trigger={false} cursors={cursors} onCursors={setCursors}
        onRange={() => undefined} testid="roll-chart" />
    </Panel>
  );
}

export function Scope() {
  useEffect(() => {
    void pollScope();
    const id = setInterval(() => void pollScope(), SCOPE_PERIOD_MS);
    return () => clearInterval(id);
  }, []);
  return (
    <div class="scope">
      <div class="scope-side">
        <ScopeSetup />
      </div>
      <div class="scope-main">
        <CommandStrip />
        {scopeStatus.value?.state === "roll" ? <RollView /> : <CaptureView />}
        <TraceLibrary />
      </div>
    </div>
  );
}
