// An assistant's series (the lag over time) in uPlot, with reference levels drawn as dashed
// lines (the lag kv alone would give, the measured mean): fixed data, drawn once per result.
// `more` overlays series on the same x samples (the loop gain's responses, one per kv).
import { useEffect, useRef } from "preact/hooks";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import type { AssistSeries } from "../api/types";
import { fmt, tickLabels } from "../ui/format";
import { followWidth } from "../ui/plot";
import { COLOURS } from "./LivePlot";

/** A horizontal line across the chart: a level to compare the series with. */
export interface Level {
  label: string;
  value: number;
}

const HEIGHT = 240;

export function AssistChart(props: {
  series: AssistSeries;
  levels: Level[];
  testid?: string;
  more?: AssistSeries[];
  label?: (s: AssistSeries) => string;
  xLabel?: string;
  yLabel?: string;
}) {
  const box = useRef<HTMLDivElement>(null);
  const { series, levels } = props;
  const more = props.more ?? [];
  const label = props.label ?? ((s: AssistSeries) => s.name);
  useEffect(() => {
    const el = box.current;
    if (!el) return;
    const unit = series.y_unit ? ` [${series.y_unit}]` : "";
    const opts: uPlot.Options = {
      width: Math.max(300, el.clientWidth),
      height: HEIGHT,
      series: [
        { label: props.xLabel ?? `t [${series.x_unit || "s"}]`, value: (_u, v) => fmt(v, 3) },
        ...[series, ...more].map((s, i) => ({
          label: `${label(s)}${unit}`,
          stroke: COLOURS[i % COLOURS.length],
          width: 1.5,
          points: { show: series.x.length < 20 }, // a few points over kv: each one is a run
          value: (_u: uPlot, v: number | null) => fmt(v, 5),
        })),
        ...levels.map((l, i) => ({
          label: `${l.label}${unit}`,
          stroke: COLOURS[(i + 1 + more.length) % COLOURS.length],
          width: 1.25,
          dash: [6, 4],
          value: (_u: uPlot, v: number | null) => fmt(v, 5),
        })),
      ],
      scales: { x: { time: false } },
      axes: [
        { label: props.xLabel ?? `time on the copy [${series.x_unit || "s"}]`, values: (_u, splits) => tickLabels(splits) },
        { label: `${props.yLabel ?? series.name}${unit}`, values: (_u, splits) => tickLabels(splits), size: 70 },
      ],
    };
    // overlays sample the same times (one sweep, one record length): aligned by index
    const aligned = more.map((m) => series.x.map((_x, i) => m.y[i] ?? null));
    const data = [series.x, series.y, ...aligned, ...levels.map((l) => series.x.map(() => l.value))] as uPlot.AlignedData;
    const plot = new uPlot(opts, data, el);
    return followWidth(plot, el, HEIGHT);
  }, [series, more.length, levels.map((l) => `${l.label}=${l.value}`).join(",")]);
  return <div class="assist-chart" ref={box} data-testid={props.testid} />;
}
