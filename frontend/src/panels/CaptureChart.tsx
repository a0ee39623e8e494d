// A captured record in uPlot: time from the trigger, a trigger marker at t = 0, two cursors
// (click sets A, shift-click sets B, drag a line to move it), drag or wheel to zoom, buttons
// to pan, double-click for the whole record, and an overlay trace drawn dashed behind. One y
// axis per quantity (or per unit, shared), booleans as digital lanes below the analog area
// (ui/scopeAxes.ts).
import { useEffect, useRef, useState } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { analogRange, type ChannelShape, laneBit, laneValue, scopeLayout, yAxes } from "../ui/scopeAxes";
import { COLOURS } from "./LivePlot";

export interface Series extends ChannelShape {
  data: Float64Array;
}

export interface Overlay {
  label: string;
  t: Float64Array;
  channels: Map<string, Float64Array>;
}

export type Cursors = [number | null, number | null];
const CHART_HEIGHT = 330;
const SHARE_KEY = "inbetrieb.scope.shareY";

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
  // one y axis per unit instead of one per quantity (kept in this browser)
  const [shareY, setShareY] = useState(() => localStorage.getItem(SHARE_KEY) === "1");
  const box = useRef<HTMLDivElement>(null);
  const plot = useRef<uPlot | null>(null);
  const cursorsRef = useRef(props.cursors);
  cursorsRef.current = props.cursors;
  const cb = useRef(props);
  cb.current = props;

  const overlaid = props.overlay ? props.series.filter((s) => props.overlay?.channels.has(s.name)) : [];
  const layout = scopeLayout(props.series, shareY);
  // a boolean sample becomes its lane's level; analog samples stay as they are
  const drawn = (i: number, y: ArrayLike<number | null>): (number | null)[] | number[] => {
    const lane = layout.laneOf[i];
    if (lane === null) return y as unknown as number[];
    return Array.from(y, (v) => laneValue(v, lane, layout.lanes));
  };
  const aligned = (): uPlot.AlignedData => {
    const { t, series, overlay } = props;
    return [
      t as unknown as number[],
      ...series.map((s, i) => drawn(i, s.data)),
      ...overlaid.map((s) => drawn(series.indexOf(s), onGrid(t, overlay!.t, overlay!.channels.get(s.name)!))),
    ];
  };
  const structure = `${props.series.map((s) => `${s.name}:${s.unit}:${s.kind}`).join(",")}|${overlaid.length}|${shareY}`;

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

    const { laneOf, digitalShare } = layout;
    const stepped = uPlot.paths.stepped!({ align: 1 });
    const valueOf = (i: number) => (_u: uPlot, v: number | null) => (laneOf[i] === null ? fmt(v, 4) : String(laneBit(v) ?? "—"));
    const bools = series.filter((_s, i) => laneOf[i] !== null);
    const y = yAxes(layout, bools, (_key, min, max) => analogRange(min, max, digitalShare).slice(0, 2) as [number, number]);
    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height: CHART_HEIGHT, // the legend (cursor values) goes below, outside this height
      series: [
        { label: "t [s]", value: (_u, v) => fmt(v, 4) },
        ...series.map((s, i) => ({
          label: s.unit ? `${s.name} [${s.unit}]` : s.name,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.25,
          ...y.series[i],
          ...(laneOf[i] !== null ? { paths: stepped } : {}),
          value: valueOf(i),
        })),
        ...overlaid.map((s) => {
          const i = series.indexOf(s);
          return {
            label: `${overlay!.label}: ${s.name}`,
            stroke: COLOURS[i % COLOURS.length] + "99",
            width: 1.25,
            dash: [6, 4],
            ...y.series[i],
            ...(laneOf[i] !== null ? { paths: stepped } : {}),
            value: valueOf(i),
          };
        }),
      ],
      scales: { x: { time: false }, ...y.scales },
      axes: [{ label: "time from trigger [s]", values: (_u, splits) => tickLabels(splits) }, ...y.axes],
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
    <div class="capture-chart" data-testid={props.testid} data-y-units={layout.scales.map((sc) => sc.unit).join("|")}
      data-y-scales={layout.scales.map((sc) => sc.label).join("|")}
      data-lanes={props.series.filter((_s, i) => layout.laneOf[i] !== null).map((s) => s.name).join("|")}>
      <div class="plot-tools">
        <button type="button" title="pan left" onClick={() => span((a, b) => [a - (b - a) / 2, b - (b - a) / 2])}>◀</button>
        <button type="button" title="pan right" onClick={() => span((a, b) => [a + (b - a) / 2, b + (b - a) / 2])}>▶</button>
        <button type="button" title="zoom in" onClick={() => span((a, b) => [a + (b - a) / 4, b - (b - a) / 4])}>+</button>
        <button type="button" title="zoom out" onClick={() => span((a, b) => [a - (b - a) / 2, b + (b - a) / 2])}>−</button>
        <button type="button" data-testid="chart-whole" onClick={whole}>whole record</button>
        <label title="one y axis for each unit instead of one for each quantity (position, lag, speed …)">
          <input type="checkbox" data-testid="chart-share-y" checked={shareY}
            onChange={(e) => {
              const on = (e.target as HTMLInputElement).checked;
              localStorage.setItem(SHARE_KEY, on ? "1" : "0");
              setShareY(on);
            }} /> one axis per unit
        </label>
        <span class="hint">drag or wheel: zoom · click: cursor A · shift-click: cursor B</span>
      </div>
      <div class="capture-box" ref={box} />
    </div>
  );
}
