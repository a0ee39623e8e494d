// Acceleration over speed in uPlot: the measured or typed points as dots and the fitted
// curves as lines, each on its own x (joined into one aligned table, gaps left open).
import { useEffect, useRef } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import type { AssistSeries } from "../api/types";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { COLOURS } from "./LivePlot";

const HEIGHT = 280;

/** `points` drawn as dots, each of `curves` as a line, over the union of their speeds. */
export function CurveChart(props: { points: AssistSeries; curves: AssistSeries[]; testid?: string }) {
  const box = useRef<HTMLDivElement>(null);
  const { points, curves } = props;
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const all = [points, ...curves];
    const xs = [...new Set(all.flatMap((s) => s.x))].sort((a, b) => a - b);
    const index = new Map(xs.map((x, i) => [x, i]));
    const column = (s: AssistSeries) => {
      const col: (number | null)[] = xs.map(() => null);
      s.x.forEach((x, i) => (col[index.get(x) as number] = s.y[i]));
      return col;
    };
    const xu = points.x_unit || "°/s";
    const yu = points.y_unit || "°/s²";
    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height: HEIGHT,
      series: [
        { label: `n [${xu}]`, value: (_u, v) => fmt(v, 0) },
        { label: points.name, stroke: "#222", width: 0, points: { show: true, size: 7, fill: "#222" }, value: (_u, v) => fmt(v, 0) },
        ...curves.map((c, i) => ({
          label: c.name,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.75,
          spanGaps: true,
          points: { show: false },
          value: (_u: uPlot, v: number | null) => fmt(v, 0),
        })),
      ],
      scales: { x: { time: false } },
      axes: [
        { label: `speed n [${xu}]`, values: (_u, splits) => tickLabels(splits) },
        { label: `acceleration a [${yu}]`, values: (_u, splits) => tickLabels(splits), size: 70 },
      ],
    };
    const data = [xs, ...all.map(column)] as uPlot.AlignedData;
    const plot = new uPlot(opts, data, el);
    return followWidth(plot, el, HEIGHT);
  }, [points, curves]);
  return <div class="assist-chart" ref={box} data-testid={props.testid} />;
}
