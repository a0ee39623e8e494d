// The Scope workspace: setup and library beside the capture on screen (or the rolling
// window), with cursors, measurements, an overlaid stored trace and the parameter differences.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { TraceCompare } from "../api/types";
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
import { CaptureChart, type Cursors, type Series } from "./CaptureChart";
import { ScopeSetup } from "./ScopeSetup";
import { TraceLibrary, when } from "./TraceLibrary";
import { TraceView } from "./TraceView";

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

function CaptureView() {
  const [trace, setTrace] = useState<LoadedTrace | null>(null);
  const [overlay, setOverlay] = useState<LoadedTrace | null>(null);
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

  const d = trace?.detail;
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
        <TraceView trace={trace} overlay={overlay}
          top={!d.stored ? <SaveForm id={d.id} onSaved={() => void refreshLibrary().then(() => loadTrace(d.id).then(setTrace))} /> : null}>
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
        </TraceView>
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
