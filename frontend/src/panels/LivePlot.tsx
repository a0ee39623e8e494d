// One live plot: chosen signals (subscribed by state/plots.ts, on screen or not) over a 1–30 s
// window, drawn with uPlot at most as often as the refresh rate says (state/plots.ts) and only
// when new samples arrived; a y axis per quantity (or per unit, shared), booleans as lanes
// (ui/scopeAxes.ts); pause, drag-zoom (pauses), autoscale, cursor readout in the legend, and
// the newest value of every trace under the chart. A signal added keeps the others' history
// and starts empty: the samples it has no history for are gaps, not NaN (uPlot's range of a
// series that starts with NaN is NaN, and the whole chart went blank until the window filled).
import { useEffect, useRef, useState } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { type PlotConfig, plotRate } from "../state/plots";
import { status } from "../state/session";
import { catalogue, frameListeners, rings } from "../state/telemetry";
import { fmt, tickLabels } from "../ui/format";
import { drawLoop } from "../ui/drawLoop";
import { analogRange, type ChannelShape, laneBit, laneValue, scopeLayout, yAxes } from "../ui/scopeAxes";
import { SignalPicker } from "../ui/SignalPicker";

export const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
export const fps = { frames: 0, draws: 0 }; // read by bench/ui.py through window.inbetrieb

function unitOf(name: string): string {
  return catalogue.value.find((s) => s.name === name)?.unit ?? "";
}

function shapeOf(name: string): ChannelShape {
  const s = catalogue.value.find((x) => x.name === name);
  return { name, unit: s?.unit ?? "", kind: s?.kind ?? "float" };
}

/** A ring column as uPlot draws it: the samples before its first one (a signal added to the
 * plot has no history) as gaps. */
function gapsForMissing(col: Float64Array): ArrayLike<number | null> {
  if (!col.length || !Number.isNaN(col[0])) return col;
  let k = 0;
  while (k < col.length && Number.isNaN(col[k])) k++;
  const out: (number | null)[] = new Array(col.length);
  for (let i = 0; i < col.length; i++) out[i] = i < k ? null : col[i];
  return out;
}

/** The newest value as read: a spindle's position within 0…360° with its whole revolutions
 * apart (537 242° reads 122.000 (1492 rev)), as the machine view and the C axis show it. */
function latestText(name: string, v: number): string {
  const spindle = catalogue.value.find((x) => x.name === name)?.axis;
  const turning = spindle && status.value?.axes.find((a) => a.name === spindle)?.kind === "spindle";
  if (!turning || !/\.pos_(cmd|act|true)_deg$/.test(name) || !Number.isFinite(v)) return fmt(v, 3);
  const revs = Math.floor(v / 360);
  return `${fmt(v - 360 * revs, 3)} (${revs} rev)`;
}

type Ranges = Record<string, [number, number]>; // frozen y ranges by scale key

export function LivePlot(props: { config: PlotConfig; onChange: (c: PlotConfig) => void; onRemove?: () => void }) {
  const { config } = props;
  const box = useRef<HTMLDivElement>(null);
  const plot = useRef<uPlot | null>(null);
  const [paused, setPaused] = useState(false);
  const [frozen, setFrozen] = useState<Ranges | null>(null); // null: autoscale
  const [latest, setLatest] = useState<number[]>([]);
  const pausedRef = useRef(paused);
  pausedRef.current = paused;

  // (re)build the chart when its traces change
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const shapes = config.signals.map(shapeOf);
    const layout = scopeLayout(shapes, config.shareY);
    const { laneOf, lanes, digitalShare } = layout;
    const bools = shapes.filter((_s, i) => laneOf[i] !== null);
    const range = (key: string, min: number, max: number): [number, number] =>
      frozen?.[key] ?? (analogRange(min, max, digitalShare).slice(0, 2) as [number, number]);
    const y = yAxes(layout, bools, range);
    const stepped = uPlot.paths.stepped!({ align: 1 });
    const opts: uPlot.Options = {
      width: Math.max(200, el.clientWidth),
      height: Math.max(160, el.clientHeight),
      series: [
        { label: "t [s]", value: (_u, v) => fmt(v, 3) },
        ...config.signals.map((s, i) => ({
          label: unitOf(s) ? `${s} [${unitOf(s)}]` : s,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.25,
          dash: i >= COLOURS.length ? [6, 3] : undefined, // colour is not the only difference
          ...y.series[i],
          ...(laneOf[i] !== null ? { paths: stepped } : {}),
          value: (_u: uPlot, v: number | null) => (laneOf[i] === null ? fmt(v, 4) : String(laneBit(v) ?? "—")),
        })),
      ],
      scales: { x: { time: false }, ...y.scales },
      axes: [{ label: "simulated time [s]", values: (_u, splits) => tickLabels(splits) }, ...y.axes],
      cursor: { drag: { x: true, y: false } },
      legend: { live: true },
      hooks: {
        setSelect: [(u) => u.select.width > 0 && setPaused(true)], // zooming freezes the view
      },
    };
    const drawn = (cols: Float64Array[]): uPlot.AlignedData => [
      cols[0] as unknown as number[],
      ...cols.slice(1).map((c, i) => {
        const lane = laneOf[i];
        return lane === null ? (gapsForMissing(c) as number[]) : Array.from(c, (v) => laneValue(Number.isNaN(v) ? null : v, lane, lanes));
      }),
    ];
    const u = new uPlot(opts, [[], ...config.signals.map(() => [])], el);
    plot.current = u;
    const ro = new ResizeObserver(() => u.setSize({ width: Math.max(200, el.clientWidth), height: Math.max(160, el.clientHeight) }));
    ro.observe(el);
    let lastLatest = 0;
    const loop = drawLoop((now) => {
      if (pausedRef.current) return;
      fps.frames++;
      const r = rings.value;
      u.setData(drawn(r.window(config.windowS, config.signals)));
      fps.draws++;
      if (now - lastLatest > 200) {
        lastLatest = now;
        setLatest(config.signals.map((s) => r.latest(s)));
      }
    }, plotRate.value);
    const onFrame = () => loop.kick(); // new samples: draw them
    frameListeners.add(onFrame);
    loop.kick();
    return () => {
      frameListeners.delete(onFrame);
      loop.stop();
      ro.disconnect();
      u.destroy();
      plot.current = null;
    };
  }, [config.signals.join(","), config.windowS, config.shareY, frozen, catalogue.value.length, plotRate.value]);

  function toggleAutoscale() {
    const u = plot.current;
    if (frozen || !u) return setFrozen(null);
    const shown: Ranges = {}; // freeze every scale as shown
    for (const [key, sc] of Object.entries(u.scales)) {
      if (key !== "x" && sc.min != null && sc.max != null) shown[key] = [sc.min, sc.max];
    }
    setFrozen(shown);
  }

  return (
    <div class="liveplot" data-testid={`plot-${config.id}`} data-y-scales={scopeLayout(config.signals.map(shapeOf), config.shareY).scales.map((sc) => sc.label).join("|")}>
      <div class="plot-tools">
        <SignalPicker chosen={config.signals} onChange={(signals) => props.onChange({ ...config, signals })} />
        <label>
          Window{" "}
          <input type="range" min={1} max={30} step={1} value={config.windowS} aria-label="window in seconds"
            onChange={(e) => props.onChange({ ...config, windowS: Number((e.target as HTMLInputElement).value) })} />
          {config.windowS} s
        </label>
        <button type="button" data-testid="plot-pause" aria-pressed={paused} onClick={() => setPaused(!paused)}>
          {paused ? "▶ Resume" : "❚❚ Pause"}
        </button>
        <label>
          <input type="checkbox" checked={!frozen} onChange={toggleAutoscale} /> autoscale
        </label>
        <label title="one y axis for each unit instead of one for each quantity (position, lag, speed …)">
          <input type="checkbox" data-testid="plot-share-y" checked={!!config.shareY}
            onChange={(e) => props.onChange({ ...config, shareY: (e.target as HTMLInputElement).checked })} /> one axis per unit
        </label>
        {props.onRemove ? (
          <button type="button" class="link" onClick={props.onRemove} aria-label="remove plot">
            ✕
          </button>
        ) : null}
      </div>
      <div class="plot-box" ref={box} />
      <div class="latest">
        {config.signals.map((s, i) => (
          <span key={s} style={{ borderColor: COLOURS[i % COLOURS.length] }}>
            {s} = <b data-testid={`latest-${s}`}>{latestText(s, latest[i])}</b> {unitOf(s)}
          </span>
        ))}
      </div>
    </div>
  );
}
