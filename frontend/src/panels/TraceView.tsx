// One trace on screen: its chart with cursors and measurements, the channels drawn (a flight
// recorder's trace holds every axis: it opens on the axis that raised the error), the events
// and the parameters as they were. The Scope's capture and an offline bundle's alarm traces.
import type { ComponentChildren } from "preact";
import { useMemo, useState } from "preact/hooks";
import type { TraceDetail } from "../api/types";
import type { LoadedTrace } from "../state/scope";
import { fmt } from "../ui/format";
import { CaptureChart, type Cursors, type Overlay, type Series } from "./CaptureChart";
import { Measurements } from "./Measurements";
import { TraceLinks, when } from "./TraceLibrary";

const READABLE = 6; // more channels than this in one chart: a flight trace opens on one axis

/** The channels drawn when a trace opens: all of a capture (its channels were chosen); of a
 * flight recorder's trace those of the axis its error names (else the first axis). */
export function defaultChannels(d: TraceDetail): Set<string> {
  const names = d.channels.map((c) => c.name);
  if (d.source !== "flight" || names.length <= READABLE) return new Set(names);
  const axisOf = (n: string) => (n.includes(".") ? n.split(".")[0] : "");
  const erring = d.events.find((e) => e.error && names.some((n) => axisOf(n) === e.axis))?.axis;
  const axis = erring ?? axisOf(names.find((n) => axisOf(n)) ?? "");
  const mine = names.filter((n) => axisOf(n) === axis);
  return new Set(mine.length ? mine : names.slice(0, READABLE));
}

/** Which of the trace's channels are drawn: one toggle each, grouped by axis. */
function ChannelPicker(props: { detail: TraceDetail; shown: Set<string>; onChange: (s: Set<string>) => void }) {
  const { detail, shown, onChange } = props;
  if (detail.channels.length <= 1) return null;
  const toggle = (name: string) => {
    const next = new Set(shown);
    if (!next.delete(name)) next.add(name);
    if (next.size) onChange(next); // one stays drawn
  };
  return (
    <div class="channel-picker" data-testid="channel-picker" aria-label="channels drawn">
      <span class="hint">
        {shown.size} of {detail.channels.length} drawn:
      </span>
      {detail.channels.map((c) => (
        <button key={c.name} type="button" aria-pressed={shown.has(c.name)} data-testid="channel-toggle" data-channel={c.name}
          class={shown.has(c.name) ? "chip on" : "chip"} onClick={() => toggle(c.name)}>
          {c.name}
        </button>
      ))}
      {shown.size < detail.channels.length ? (
        <button type="button" class="link" data-testid="channel-all" onClick={() => onChange(new Set(detail.channels.map((c) => c.name)))}>
          all
        </button>
      ) : null}
    </div>
  );
}

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

function CursorTable(props: { trace: LoadedTrace; cursors: Cursors; shown: Set<string> }) {
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
        {trace.detail.channels.filter((c) => props.shown.has(c.name)).map((c) => {
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


/** A trace with its chart, cursors, measurements and facts; `overlay` drawn dashed behind;
 * `top` below its head (a form to save it), `children` at the end (the comparison). */
export function TraceView(props: {
  trace: LoadedTrace;
  overlay: LoadedTrace | null;
  top?: ComponentChildren;
  children?: ComponentChildren;
}) {
  const { trace, overlay } = props;
  const d = trace.detail;
  // cursors, zoom and the channels drawn belong to one trace: the next capture starts afresh
  // (its chart keeps its frame when its channels are the same, only the samples change)
  const [mine, setMine] = useState<{ id: string; cursors: Cursors; range: [number, number] | null; shown: Set<string> } | null>(null);
  const own = mine?.id === d.id ? mine : { id: d.id, cursors: [null, null] as Cursors, range: null, shown: defaultChannels(d) };
  const { cursors, range, shown } = own;
  const setCursors = (c: Cursors) => setMine({ ...own, cursors: c });
  const setRange = (r: [number, number]) => setMine({ ...own, range: r });
  const setShown = (s: Set<string>) => setMine({ ...own, shown: s });
  const series: Series[] = d.channels
    .filter((c) => shown.has(c.name))
    .map((c) => ({ name: c.name, unit: c.unit, kind: c.kind, data: trace.channels.get(c.name)! }));
  // one object per overlay: the chart rebuilds when it changes identity
  const ov = useMemo<Overlay | null>(
    () => (overlay ? { label: overlay.detail.name || "overlay", t: overlay.t, channels: overlay.channels } : null),
    [overlay],
  );
  // a drive-rate capture: its samples are drive steps (their signals are `<axis>.drive.*`)
  const drive = d.channels.some((c) => c.name.split(".")[1] === "drive");
  return (
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
      {props.top}
      <ChannelPicker detail={d} shown={shown} onChange={setShown} />
      <CaptureChart t={trace.t} series={series} overlay={ov} trigger={d.trigger_cycle !== null} cursors={cursors}
        onCursors={setCursors} onRange={setRange} testid="capture-chart" />
      <div class="capture-below">
        <CursorTable trace={trace} cursors={cursors} shown={shown} />
        <Measurements detail={d} cursors={cursors} range={range} compare={overlay?.detail ?? null} />
      </div>
      <RecordFacts detail={d} />
      {props.children}
    </div>
  );
}
