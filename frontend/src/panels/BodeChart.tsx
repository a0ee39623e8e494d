// A measured frequency response as an engineer reads it: magnitude (dB) and phase (°) over a
// logarithmic frequency axis, the coherence below, the resonances, crossovers and bandwidth
// the run found marked as vertical lines; earlier runs overlaid for before/after.
import { useEffect, useRef, useState } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import type { AssistResult, AssistRun, AssistSeries } from "../api/types";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { CompareWith, FigureDeltas, runLabel } from "./CompareRun";
import { COLOURS } from "./LivePlot";

/** Figures drawn as vertical marks, with their short label. */
const MARKS: [RegExp, string][] = [
  [/^resonance_(\d+)_hz$/, "f_r"],
  [/^anti_resonance_(\d+)_hz$/, "f_ar"],
  [/^crossover_hz$/, "f_c"],
  [/^phase_crossover_hz$/, "f_180"],
  [/^bandwidth_hz$/, "f_bw"],
];

interface Mark {
  label: string;
  hz: number;
}

/** The frequencies the run named, as marks. */
export function bodeMarks(r: AssistResult): Mark[] {
  const out: Mark[] = [];
  for (const f of r.figures) {
    for (const [re, label] of MARKS) {
      const m = re.exec(f.name);
      if (m) out.push({ label: m[1] && m[1] !== "1" ? `${label}${m[1]}` : label, hz: f.value });
    }
  }
  return out;
}

const seriesOf = (r: AssistResult, name: string): AssistSeries | undefined => r.series.find((s) => s.name === name);

/** Log-spaced ticks' labels: 1, 2, 5, 10, … Hz (uPlot's log splits give every decade step). */
const hzLabels = (splits: number[]) =>
  splits.map((v) => {
    const lead = v / 10 ** Math.floor(Math.log10(v) + 1e-9);
    return [1, 2, 5].some((d) => Math.abs(lead - d) < 1e-6) ? (v >= 1000 ? `${v / 1000}k` : `${v}`) : "";
  });

/** Phase ticks at multiples of 90° (180° or 360° over a wide span). */
function phaseSplits(_u: uPlot, _axis: number, lo: number, hi: number): number[] {
  const step = hi - lo > 1440 ? 360 : hi - lo > 720 ? 180 : 90;
  const out: number[] = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi; v += step) out.push(v);
  return out;
}

function drawMarks(marks: Mark[]) {
  return (u: uPlot) => {
    const ctx = u.ctx;
    const { top, height } = u.bbox;
    ctx.save();
    ctx.font = `${11 * devicePixelRatio}px sans-serif`;
    marks.forEach((m, i) => {
      const x = u.valToPos(m.hz, "x", true);
      if (!Number.isFinite(x)) return;
      ctx.strokeStyle = "#555";
      ctx.setLineDash([4 * devicePixelRatio, 3 * devicePixelRatio]);
      ctx.beginPath();
      ctx.moveTo(x, top);
      ctx.lineTo(x, top + height);
      ctx.stroke();
      ctx.fillStyle = "#333";
      ctx.fillText(`${m.label} ${fmt(m.hz, 1)} Hz`, x + 3 * devicePixelRatio, top + (12 + 12 * (i % 3)) * devicePixelRatio);
    });
    ctx.restore();
  };
}

function BodePart(props: {
  runs: AssistResult[];
  name: string;
  unit: string;
  height: number;
  marks: Mark[];
  labels: string[];
  testid: string;
  range?: [number, number];
  dashed?: number; // index of the run drawn dashed (a prediction over the measurement)
}) {
  const box = useRef<HTMLDivElement>(null);
  const { runs, name, unit, height, marks, labels } = props;
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const curves = runs.map((r) => seriesOf(r, name)).filter((s): s is AssistSeries => !!s && s.x.length > 0);
    if (!curves.length) return;
    // the runs' frequencies differ: one x axis with every frequency, each curve null elsewhere
    const xs = [...new Set(curves.flatMap((c) => c.x))].sort((a, b) => a - b);
    const data = [
      xs,
      ...curves.map((c) => {
        const at = new Map(c.x.map((x, i) => [x, c.y[i]]));
        return xs.map((x) => at.get(x) ?? null);
      }),
    ] as uPlot.AlignedData;
    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height,
      series: [
        { label: "f [Hz]", value: (_u, v) => fmt(v, 1) },
        ...curves.map((_c, i) => ({
          label: `${labels[i] ?? `run ${i + 1}`}${unit ? ` [${unit}]` : ""}`,
          stroke: COLOURS[i % COLOURS.length],
          width: i === 0 ? 1.75 : 1.25,
          ...(i === props.dashed ? { dash: [6, 4], width: 2 } : {}),
          spanGaps: true,
          value: (_u: uPlot, v: number | null) => fmt(v, 2),
        })),
      ],
      scales: {
        x: { time: false, distr: 3, log: 10, range: [xs[0], xs[xs.length - 1]] },
        ...(props.range ? { y: { range: props.range } } : {}),
      },
      axes: [
        { label: "frequency [Hz]", values: (_u, splits) => hzLabels(splits) },
        {
          label: `${name.replace(/_db$|_deg$/, "")}${unit ? ` [${unit}]` : ""}`,
          values: (_u, splits) => tickLabels(splits),
          size: 60,
          // the coherence on 0 … 1; the phase at multiples of 90° (180° when it spans more)
          ...(props.range ? { splits: () => [0, 0.5, 1] } : {}),
          ...(unit === "°" ? { splits: phaseSplits } : {}),
        },
      ],
      hooks: { draw: [drawMarks(marks)] },
    };
    const plot = new uPlot(opts, data, el);
    return followWidth(plot, el, height);
  }, [runs.map((r) => r.series.length + (seriesOf(r, name)?.y[0] ?? 0)).join(","), marks.map((m) => m.hz).join(",")]);
  return <div class="assist-chart bode-part" ref={box} data-testid={props.testid} />;
}

/** The Bode plot of `result`, with `earlier` runs overlaid (labelled by `labels`). */
export function BodeChart(props: { result: AssistResult; earlier?: AssistResult[]; labels?: string[]; dashed?: number }) {
  const runs = [props.result, ...(props.earlier ?? [])];
  const marks = bodeMarks(props.result);
  const labels = props.labels ?? runs.map((_r, i) => (i === 0 ? "this run" : `earlier ${i}`));
  return (
    <div class="bode" data-testid="bode" data-runs={runs.length}
      data-marks={marks.map((m) => `${m.label}:${m.hz.toFixed(1)}`).join(" ")}>
      <BodePart runs={runs} name="magnitude_db" unit="dB" height={240} marks={marks} labels={labels} testid="bode-magnitude" dashed={props.dashed} />
      <BodePart runs={runs} name="phase_deg" unit="°" height={220} marks={marks} labels={labels} testid="bode-phase" dashed={props.dashed} />
      <BodePart runs={runs} name="coherence" unit="" height={160} marks={[]} labels={labels} testid="bode-coherence" range={[0, 1.05]} />
    </div>
  );
}

/** The Bode plot with a choice of an earlier run of the same measurement on the same axis to
 * overlay (before/after a change). */
export function BodeView(props: { result: AssistResult }) {
  const r = props.result;
  const measurement = r.inputs.measurement;
  const [earlier, setEarlier] = useState<AssistRun | null>(null);
  const same = earlier && earlier.result.inputs.measurement === measurement ? earlier : null;
  return (
    <div class="bode-view">
      <BodeChart result={r} earlier={same ? [same.result] : []} labels={["this run", same ? runLabel(same) : ""]} />
      <CompareWith result={r} testid="bode-compare" onPick={setEarlier}
        matches={(x) => (x.measurement ?? null) === (measurement ?? null)} />
      {earlier && !same ? (
        <p class="hint" data-testid="bode-compare-other">
          Run #{earlier.id} measured something else: compare runs of the same measurement.
        </p>
      ) : null}
      {same ? <FigureDeltas now={r} before={same.result} label={`#${same.id}`} skip={NOT_COMPARED} /> : null}
    </div>
  );
}

const NOT_COMPARED = new Set(["measured_s", "coherence_min"]);
