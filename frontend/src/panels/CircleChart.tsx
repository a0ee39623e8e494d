// The circularity test's polar plot (ISO 230-4): the radial deviation about the least-squares
// centre, magnified about the nominal circle (µm per division), CCW and CW overlaid, an earlier
// run drawn faint beneath (before/after), with the plane's axes named at 0° and 90°.
import { useState } from "preact/hooks";
import type { AssistResult, AssistRun, AssistSeries } from "../api/types";
import { fmt } from "../ui/format";
import { CompareWith, FigureDeltas, runLabel } from "./CompareRun";

const SIZE = 360; // the plot's square (viewBox units; it scales with the panel)
const BASE = 100; // the radius the nominal circle is drawn at
const DIVISIONS = 4; // rings inside and outside the nominal circle
const MARGIN = 16; // between the outer ring and the edge: the axes' names
const COLOURS: Record<string, string> = { CCW: "#1565c0", CW: "#c62828" };
const STEPS = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];

/** µm per division: the smallest step that keeps every point within the rings. */
export function division(series: AssistSeries[]): number {
  const worst = Math.max(0, ...series.flatMap((s) => s.y.map((v) => Math.abs(v))));
  return STEPS.find((d) => d * DIVISIONS >= worst) ?? STEPS[STEPS.length - 1];
}

function path(s: AssistSeries, perPx: number): string {
  const pts = s.x.map((deg, i) => {
    const r = BASE + s.y[i] / perPx;
    const t = (deg * Math.PI) / 180;
    return `${(SIZE / 2 + r * Math.cos(t)).toFixed(1)},${(SIZE / 2 - r * Math.sin(t)).toFixed(1)}`;
  });
  return pts.length ? `M${pts.join("L")}Z` : "";
}

/** The polar plot of `result` (and of `earlier`, faint), the plane's axes named at 0° and 90°. */
export function CircleChart(props: { result: AssistResult; earlier?: AssistResult | null; testid?: string }) {
  const r = props.result;
  const axes = String(r.inputs.axis ?? "");
  const [first, second] = [axes.slice(0, 1), axes.slice(1)];
  const series = r.series.filter((s) => s.x_unit === "°");
  const before = (props.earlier?.series ?? []).filter((s) => s.x_unit === "°");
  const div = division([...series, ...before]);
  const ring = (SIZE / 2 - MARGIN - BASE) / DIVISIONS; // per division
  const perPx = div / ring; // µm per px
  const c = SIZE / 2;
  return (
    <figure class="circle-chart" data-testid={props.testid ?? "circle-chart"} data-um-per-division={div}>
      <svg viewBox={`0 0 ${SIZE} ${SIZE}`} role="img"
        aria-label={`polar plot of the radial deviation, ${fmt(div, 1)} µm per division`}>
        {Array.from({ length: 2 * DIVISIONS + 1 }, (_, i) => i - DIVISIONS).map((k) => (
          <circle key={k} cx={c} cy={c} r={BASE + k * ring} class={k === 0 ? "nominal" : "ring"} />
        ))}
        <line x1={c - BASE - DIVISIONS * ring} y1={c} x2={c + BASE + DIVISIONS * ring} y2={c} class="ring" />
        <line x1={c} y1={c - BASE - DIVISIONS * ring} x2={c} y2={c + BASE + DIVISIONS * ring} class="ring" />
        <text x={SIZE - 2} y={c + 14} text-anchor="end" class="axis-name">+{first}</text>
        <text x={c + 4} y={11} class="axis-name">+{second}</text>
        {before.map((s) => (
          <path key={`b-${s.name}`} d={path(s, perPx)} class="earlier" stroke={COLOURS[s.name] ?? "#666"} data-series={`before-${s.name}`} />
        ))}
        {series.map((s) => (
          <path key={s.name} d={path(s, perPx)} class="now" stroke={COLOURS[s.name] ?? "#333"} data-series={s.name} />
        ))}
      </svg>
      <figcaption>
        <span data-testid="circle-scale">{fmt(div, div < 1 ? 1 : 0)} µm per division</span>
        {series.map((s) => (
          <span key={s.name} class="legend" style={{ color: COLOURS[s.name] }}>
            ━ {s.name}
          </span>
        ))}
        {before.length ? <span class="legend faint">┅ the earlier run</span> : null}
      </figcaption>
    </figure>
  );
}

/** The polar plot with a choice of an earlier circle in the same plane to lay beneath it. */
export function CircleView(props: { result: AssistResult }) {
  const r = props.result;
  const [earlier, setEarlier] = useState<AssistRun | null>(null);
  return (
    <div class="circle-view">
      <CircleChart result={r} earlier={earlier?.result} />
      <CompareWith result={r} testid="circle-compare" onPick={setEarlier} />
      {earlier ? <FigureDeltas now={r} before={earlier.result} label={runLabel(earlier)} /> : null}
    </div>
  );
}
