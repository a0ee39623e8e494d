// A captured record in uPlot: time from the trigger, a trigger marker at t = 0, two cursors
// (click sets A, shift-click sets B, drag a line to move it), drag or wheel to zoom, buttons
// to pan, double-click for the whole record, and an overlay trace drawn dashed behind.
import { useEffect, useRef } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { COLOURS } from "./LivePlot";

export interface Series {
  name: string;
  unit: string;
  data: Float64Array;
}

export interface Overlay {
  label: string;
  t: Float64Array;
  channels: Map<string, Float64Array>;
}

export type Cursors = [number | null, number | null];
const CHART_HEIGHT = 330;

/** Overlay samples on the main time grid (nearest sample; null outside the overlay). */
function onGrid(t: Float64Array, ot: Float64Array, oy: Float64Array): (number | null)[] {
  const out: (number | null)[] = new Array(t.length);
  const n = ot.length;
  const dt = n > 1 ? (ot[n - 1] - ot[0]) / (n - 1) : 1;
  for (let i = 0; i < t.length; i++) {
    const k = Math.round((t[i] - ot[0]) / dt);
    out[i] = k >= 0 && k < n ? oy[k] : null;
  }
  return out;
}

export function CaptureChart(props: {
  t: Float64Array;
  series: Series[];
  overlay: Overlay | null;
  trigger: boolean; // draw the trigger marker at t = 0
  cursors: Cursors;
  onCursors: (c: Cursors) => void;
  onRange: (r: [number, number]) => void;
  testid?: string;
}) {
  const box = useRef<HTMLDivElement>(null);
  const plot = useRef<uPlot | null>(null);
  const cursorsRef = useRef(props.cursors);
  cursorsRef.current = props.cursors;
  const cb = useRef(props);
  cb.current = props;

  const overlaid = props.overlay ? props.series.filter((s) => props.overlay?.channels.has(s.name)) : [];
  const aligned = (): uPlot.AlignedData => {
    const { t, series, overlay } = props;
    return [
      t as unknown as number[],
      ...series.map((s) => s.data as unknown as number[]),
      ...overlaid.map((s) => onGrid(t, overlay!.t, overlay!.channels.get(s.name)!)),
    ];
  };
  const structure = `${props.series.map((s) => s.name).join(",")}|${overlaid.length}`;

  // (re)build the chart when its series change; new samples of the same series only replace
  // the data (a rolling scope, the next capture of a normal-mode scope)
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const { series, overlay } = props;
    const marks = document.createElement("div");
    marks.className = "chart-marks";
    const line = (cls: string, testid: string, title: string) => {
      const d = document.createElement("div");
      d.className = cls;
      d.dataset.testid = testid;
      d.title = title;
      marks.appendChild(d);
      return d;
    };
    const trig = line("trig-marker", "trigger-marker", "trigger (t = 0)");
    const ca = line("cursor-line a", "cursor-a", "cursor A: drag to move");
    const cbx = line("cursor-line b", "cursor-b", "cursor B: drag to move");

    const place = (u: uPlot) => {
      const put = (d: HTMLDivElement, v: number | null) => {
        const x = v === null ? NaN : u.valToPos(v, "x");
        const inside = Number.isFinite(x) && x >= 0 && x <= u.over.clientWidth;
        d.style.display = inside ? "block" : "none";
        if (inside) d.style.left = `${x}px`;
        d.dataset.t = v === null ? "" : String(v);
      };
      put(trig, cb.current.trigger ? 0 : null);
      put(ca, cursorsRef.current[0]);
      put(cbx, cursorsRef.current[1]);
    };

    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height: CHART_HEIGHT, // the legend (cursor values) goes below, outside this height
      series: [
        { label: "t [s]", value: (_u, v) => fmt(v, 4) },
        ...series.map((s, i) => ({
          label: `${s.name} [${s.unit}]`,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.25,
          value: (_u: uPlot, v: number | null) => fmt(v, 4),
        })),
        ...overlaid.map((s) => ({
          label: `${overlay!.label}: ${s.name}`,
          stroke: COLOURS[series.indexOf(s) % COLOURS.length] + "99",
          width: 1.25,
          dash: [6, 4],
          value: (_u: uPlot, v: number | null) => fmt(v, 4),
        })),
      ],
      scales: { x: { time: false } },
      axes: [
        { label: "time from trigger [s]", values: (_u, splits) => tickLabels(splits) },
        {
          size: 64,
          values: (u, splits) => {
            const labels = tickLabels(splits);
            u.root.dataset.yTicks = labels.join(" | "); // what the axis reads, for tests
            return labels;
          },
        },
      ],
      cursor: { drag: { x: true, y: false } },
      legend: { live: true },
      hooks: {
        ready: [(u) => u.over.appendChild(marks)],
        draw: [place],
        setScale: [
          (u, key) => {
            if (key === "x" && u.scales.x.min != null && u.scales.x.max != null) cb.current.onRange([u.scales.x.min, u.scales.x.max]);
          },
        ],
      },
    };
    const u = new uPlot(opts, aligned(), el);
    plot.current = u;

    // click: cursor A (shift: B), unless the click ended a drag-zoom
    let downX = 0;
    const down = (e: MouseEvent) => (downX = e.clientX);
    const click = (e: MouseEvent) => {
      if (Math.abs(e.clientX - downX) > 3) return;
      const v = u.posToVal(e.clientX - u.over.getBoundingClientRect().left, "x");
      const [a, b] = cursorsRef.current;
      cb.current.onCursors(e.shiftKey ? [a, v] : [v, b]);
    };
    const wheel = (e: WheelEvent) => {
      e.preventDefault();
      const { min, max } = u.scales.x;
      if (min == null || max == null) return;
      const at = u.posToVal(e.clientX - u.over.getBoundingClientRect().left, "x");
      const f = e.deltaY < 0 ? 0.8 : 1.25;
      u.setScale("x", { min: at - (at - min) * f, max: at + (max - at) * f });
    };
    const drag = (which: 0 | 1) => (e: PointerEvent) => {
      e.stopPropagation();
      e.preventDefault();
      const move = (m: PointerEvent) => {
        const v = u.posToVal(m.clientX - u.over.getBoundingClientRect().left, "x");
        const c: Cursors = [...cursorsRef.current];
        c[which] = v;
        cb.current.onCursors(c);
      };
      const up = () => {
        window.removeEventListener("pointermove", move);
        window.removeEventListener("pointerup", up);
      };
      window.addEventListener("pointermove", move);
      window.addEventListener("pointerup", up);
    };
    ca.addEventListener("pointerdown", drag(0));
    cbx.addEventListener("pointerdown", drag(1));
    u.over.addEventListener("mousedown", down);
    u.over.addEventListener("click", click);
    u.over.addEventListener("wheel", wheel, { passive: false });
    const stop = followWidth(u, el, CHART_HEIGHT);
    return () => {
      stop();
      plot.current = null;
    };
  }, [structure, props.overlay]);

  useEffect(() => {
    plot.current?.setData(aligned());
  }, [props.t]);

  // cursors and the trigger marker move without rebuilding the chart
  useEffect(() => {
    plot.current?.redraw(false, false);
  }, [props.cursors[0], props.cursors[1], props.trigger]);

  function span(f: (min: number, max: number) => [number, number]) {
    const u = plot.current;
    if (!u || u.scales.x.min == null || u.scales.x.max == null) return;
    const [min, max] = f(u.scales.x.min, u.scales.x.max);
    u.setScale("x", { min, max });
  }
  const whole = () => span(() => [props.t[0], props.t[props.t.length - 1]]);

  return (
    <div class="capture-chart" data-testid={props.testid}>
      <div class="plot-tools">
        <button type="button" title="pan left" onClick={() => span((a, b) => [a - (b - a) / 2, b - (b - a) / 2])}>◀</button>
        <button type="button" title="pan right" onClick={() => span((a, b) => [a + (b - a) / 2, b + (b - a) / 2])}>▶</button>
        <button type="button" title="zoom in" onClick={() => span((a, b) => [a + (b - a) / 4, b - (b - a) / 4])}>+</button>
        <button type="button" title="zoom out" onClick={() => span((a, b) => [a - (b - a) / 2, b + (b - a) / 2])}>−</button>
        <button type="button" data-testid="chart-whole" onClick={whole}>whole record</button>
        <span class="hint">drag or wheel: zoom · click: cursor A · shift-click: cursor B</span>
      </div>
      <div class="capture-box" ref={box} />
    </div>
  );
}
