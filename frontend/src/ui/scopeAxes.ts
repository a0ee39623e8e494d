// How a chart (the scope's capture, a live plot) lays out its channels: one y scale and axis
// per quantity for the analog channels (a position, a lag, a speed: commanded, actual and true
// values of one quantity share theirs, so a spindle's 73 000° position does not flatten its
// 0.01° lag), or per unit when the user shares them; the boolean channels as digital lanes
// (0/1 steps, each in its own band) below the analog area. `yAxes` makes the uPlot scales,
// axes and series settings of a layout.
import type uPlot from "uplot";
import { tickLabels } from "./format";

/** A channel as the chart needs it: its unit and kind (api ChannelInfo / SignalInfo). */
export interface ChannelShape {
  name: string;
  unit: string;
  kind: "float" | "bool" | "enum";
}

/** One y scale: its uPlot key, the unit it reads in, its axis' label and side (3 left,
 * 1 right). */
export interface UnitScale {
  key: string;
  unit: string;
  label: string;
  side: 1 | 3;
}

export interface ScopeLayout {
  scales: UnitScale[];
  /** the scale key of each channel, in the channels' order */
  scaleOf: string[];
  /** lane index (0 = top lane) of each boolean channel, null for analog ones */
  laneOf: (number | null)[];
  lanes: number;
  /** the share of the plot height the digital lanes take (0 … 1) */
  digitalShare: number;
}

export const DIGITAL = "digital";
const LANE_SHARE = 0.09; // of the plot height per lane
const MAX_DIGITAL_SHARE = 0.45; // the analog area keeps at least the rest
/** A lane's high level as a share of its band (the rest is the gap to the next lane). */
export const LANE_HIGH = 0.7;

/** The unit text of an analog channel's scale: enums (state, gear, code) have none. */
export const scaleUnit = (c: ChannelShape) => c.unit || (c.kind === "enum" ? "code" : "—");

// a signal name's unit ending (X.lag_mm, S1.accel_cmd_deg_s2) and its command/actual/true part
const UNIT_END = /_(mm_min|mm_s2|deg_s2|mm|deg|rpm|pct|um|nm|s)$/;
const ROLE = /_(cmd|act|true)(?=_|$)/;

/** The quantity a channel measures, from its name: `X.pos_act_mm` and `X.pos_cmd_mm` →
 * "pos", `S1.lag_deg` → "lag"; an axis' quantity is the same quantity on another axis. */
export function quantityOf(name: string): string {
  const stem = name.slice(name.lastIndexOf(".") + 1);
  return stem.replace(UNIT_END, "").replace(ROLE, "") || stem;
}

/** Scales, lanes and the digital share for these channels: a scale per quantity (and unit),
 * or per unit only when `share`. */
export function scopeLayout(channels: ChannelShape[], share = false): ScopeLayout {
  const scales: UnitScale[] = [];
  const scaleOf: string[] = [];
  const laneOf: (number | null)[] = [];
  let lanes = 0;
  for (const c of channels) {
    if (c.kind === "bool") {
      scaleOf.push(DIGITAL);
      laneOf.push(lanes++);
      continue;
    }
    const unit = scaleUnit(c);
    const quantity = share ? "" : quantityOf(c.name);
    const key = quantity ? `y:${quantity}:${unit}` : `y:${unit}`;
    let s = scales.find((x) => x.key === key);
    if (!s) {
      // alternate the sides so two scales each get a clear axis: left, right, left …
      const label = quantity ? `${quantity} [${unit}]` : unit;
      s = { key, unit, label, side: scales.length % 2 === 0 ? 3 : 1 };
      scales.push(s);
    }
    scaleOf.push(s.key);
    laneOf.push(null);
  }
  const digitalShare = lanes === 0 ? 0 : scales.length === 0 ? 1 : Math.min(MAX_DIGITAL_SHARE, lanes * LANE_SHARE);
  return { scales, scaleOf, laneOf, lanes, digitalShare };
}

/** A boolean sample drawn in lane `lane` of `lanes` (lane 0 on top): its band's bottom plus
 * the high level for 1. */
export function laneValue(v: number | null, lane: number, lanes: number): number | null {
  return v === null || !Number.isFinite(v) ? null : lanes - 1 - lane + (v ? LANE_HIGH : 0);
}

/** The 0/1 a lane value stands for. */
export function laneBit(y: number | null): number | null {
  return y === null ? null : y - Math.floor(y + 1e-9) > LANE_HIGH / 2 ? 1 : 0;
}

/** An analog scale's range for data min…max: padded, then stretched below so the data keeps
 * clear of the digital lanes' share of the height. Returns [min, max, lowest data tick]. */
export function analogRange(min: number, max: number, digitalShare: number): [number, number, number] {
  let lo = min;
  let hi = max;
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) [lo, hi] = [0, 1];
  // a spread of round-off (a lag of ±4e−14 mm at rest) is no spread: read it as constant
  const flat = hi - lo <= 1e-12 * Math.max(1, Math.abs(lo), Math.abs(hi));
  const pad = !flat ? (hi - lo) * 0.05 : Math.max(Math.abs(hi) * 0.05, 1);
  lo -= pad;
  hi += pad;
  const below = digitalShare >= 1 ? 0 : ((hi - lo) * digitalShare) / (1 - digitalShare);
  return [lo - below, hi, lo];
}

/** The digital scale's range: the lanes fill the bottom `digitalShare` of the height. */
export function digitalRange(lanes: number, digitalShare: number): [number, number] {
  const lo = -0.15; // a little air below the lowest lane
  return [lo, lo + (lanes - lo) / Math.max(digitalShare, 1e-6)];
}

// the axes' fonts, set on every axis so their labels are measured as drawn
const AXIS_FONT = "12px system-ui, sans-serif";
const LABEL_FONT = "bold 12px system-ui, sans-serif";
const TICK_AND_GAP = 10 + 5 + 6; // tick length, gap to the text, air at the edge (px)
const LABEL_SIZE = 18;
let measurer: CanvasRenderingContext2D | null = null;

/** The width of the widest tick label in the axis font (px). */
export function labelWidth(labels: (string | null)[]): number {
  measurer ??= document.createElement("canvas").getContext("2d");
  if (!measurer) return 8 * Math.max(0, ...labels.map((l) => l?.length ?? 0));
  measurer.font = AXIS_FONT;
  return Math.max(0, ...labels.map((l) => (l ? measurer!.measureText(l).width : 0)));
}

/** An axis as wide as its widest label (a minus sign or an exponent never clipped); its
 * label (the unit) takes its own labelSize beside. */
const fitSize = (_u: uPlot, values: string[] | null): number =>
  Math.ceil(labelWidth(values ?? []) + TICK_AND_GAP);

/** A layout's uPlot y scales and axes (after the x axis), and each channel's series settings.
 * `range`: an analog scale's range from its data's min and max (autoscale), or a fixed one;
 * `bools`: the boolean channels, lane by lane. Each axis' tick labels go to the chart root's
 * `data-y-ticks` (axes joined by " ‖ ") for tests. */
export function yAxes(
  layout: ScopeLayout,
  bools: ChannelShape[],
  range: (key: string, min: number, max: number) => [number, number],
): { scales: uPlot.Scales; axes: uPlot.Axis[]; series: Partial<uPlot.Series>[] } {
  const { scales, scaleOf, lanes, digitalShare } = layout;
  const uScales: uPlot.Scales = {};
  for (const sc of scales) uScales[sc.key] = { range: (_u, min, max) => range(sc.key, min, max) };
  if (lanes) uScales[DIGITAL] = { auto: false, range: () => digitalRange(lanes, digitalShare) };
  const ticks: string[] = scales.map(() => "");
  const axes: uPlot.Axis[] = scales.map((sc, k) => ({
    scale: sc.key,
    side: sc.side,
    label: sc.label,
    labelSize: LABEL_SIZE,
    font: AXIS_FONT,
    labelFont: LABEL_FONT,
    size: fitSize,
    grid: { show: k === 0 },
    // ticks only where the analog data is, not down in the digital lanes
    filter: (u: uPlot, splits: number[]) => {
      const { min, max } = u.scales[sc.key];
      const floor = min == null || max == null ? -Infinity : min + (max - min) * digitalShare;
      return splits.map((v) => (v >= floor - 1e-9 * Math.abs(max ?? 1) ? v : null));
    },
    values: (u: uPlot, splits: number[]) => {
      const labels = tickLabels(splits);
      ticks[k] = labels.join(" | ");
      u.root.dataset.yTicks = ticks.join(" ‖ ");
      return labels;
    },
  }));
  if (lanes) {
    axes.push({
      scale: DIGITAL,
      side: 3,
      size: Math.min(170, 16 + 6.5 * Math.max(...bools.map((b) => b.name.length))),
      grid: { show: false },
      ticks: { show: false },
      splits: () => bools.map((_b, j) => lanes - 1 - j + LANE_HIGH / 2),
      values: () => bools.map((b) => b.name),
    });
  }
  const series = scaleOf.map((key) => ({ scale: key }));
  return { scales: uScales, axes, series };
}
