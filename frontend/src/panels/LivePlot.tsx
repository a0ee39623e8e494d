// One live plot: chosen signals (subscribed by state/plots.ts, on screen or not) over a 1–30 s
// window, drawn with uPlot at most as often as the refresh rate says (state/plots.ts) and only
// when new samples arrived;
// pause, drag-zoom (pauses), autoscale, cursor readout in the legend, and the newest value of
// every trace under the chart.
import { useEffect, useRef, useState } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { type PlotConfig, plotRate } from "../state/plots";
import { catalogue, frameListeners, rings } from "../state/telemetry";
import { fmt, tickLabels } from "../ui/format";
import { drawLoop } from "../ui/drawLoop";
import { SignalPicker } from "../ui/SignalPicker";

export const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
export const fps = { frames: 0, draws: 0 }; // read by bench/ui.py through window.inbetrieb

function unitOf(name: string): string {
  return catalogue.value.find((s) => s.name === name)?.unit ?? "";
}

export function LivePlot(props: { config: PlotConfig; onChange: (c: PlotConfig) => void; onRemove?: () => void }) {
  const { config } = props;
  const box = useRef<HTMLDivElement>(null);
  const plot = useRef<uPlot | null>(null);
  const [paused, setPaused] = useState(false);
  const [yRange, setYRange] = useState<[number, number] | null>(null); // null: autoscale
  const [latest, setLatest] = useState<number[]>([]);
  const pausedRef = useRef(paused);
  pausedRef.current = paused;

  // (re)build the chart when its traces change
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const opts: uPlot.Options = {
      width: Math.max(200, el.clientWidth),
      height: Math.max(160, el.clientHeight),
      series: [
        { label: "t [s]", value: (_u, v) => fmt(v, 3) },
        ...config.signals.map((s, i) => ({
          label: `${s} [${unitOf(s)}]`,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.25,
          dash: i >= COLOURS.length ? [6, 3] : undefined, // colour is not the only difference
          value: (_u: uPlot, v: number | null) => fmt(v, 4),
        })),
      ],
      scales: { x: { time: false }, y: yRange ? { auto: false, range: yRange } : { auto: true } },
      axes: [
        { label: "simulated time [s]", values: (_u, splits) => tickLabels(splits) },
        { size: 60, values: (_u, splits) => tickLabels(splits) },
      ],
      cursor: { drag: { x: true, y: false } },
      legend: { live: true },
      hooks: {
        setSelect: [(u) => u.select.width > 0 && setPaused(true)], // zooming freezes the view
      },
    };
    const u = new uPlot(opts, [[], ...config.signals.map(() => [])], el);
    plot.current = u;
    const ro = new ResizeObserver(() => u.setSize({ width: Math.max(200, el.clientWidth), height: Math.max(160, el.clientHeight) }));
    ro.observe(el);
    let lastLatest = 0;
    const loop = drawLoop((now) => {
      if (pausedRef.current) return;
      fps.frames++;
      const r = rings.value;
      u.setData(r.window(config.windowS, config.signals) as uPlot.AlignedData);
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
  }, [config.signals.join(","), config.windowS, yRange, catalogue.value.length, plotRate.value]);

  function toggleAutoscale() {
    const y = plot.current?.scales.y;
    setYRange(yRange || !y || y.min == null || y.max == null ? null : [y.min, y.max]); // freeze as shown
  }

  return (
    <div class="liveplot" data-testid={`plot-${config.id}`}>
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
          <input type="checkbox" checked={!yRange} onChange={toggleAutoscale} /> autoscale
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
            {s} = <b data-testid={`latest-${s}`}>{fmt(latest[i], 3)}</b> {unitOf(s)}
          </span>
        ))}
      </div>
    </div>
  );
}
