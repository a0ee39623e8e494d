// How a scope chart lays out its channels: one y scale and axis per unit (rpm, deg, mm …) for
// the analog channels, the boolean channels as digital lanes (0/1 steps, each in its own band)
// below the analog area. Pure: CaptureChart builds the uPlot options from it.

/** A channel as the chart needs it: its unit and kind (api ChannelInfo / SignalInfo). */
export interface ChannelShape {
  name: string;
  unit: string;
  kind: "float" | "bool" | "enum";
}

/** One y scale: its uPlot key, the unit it reads in, the axis side (3 left, 1 right). */
export interface UnitScale {
  key: string;
  unit: string;
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

/** Scales, lanes and the digital share for these channels. */
export function scopeLayout(channels: ChannelShape[]): ScopeLayout {
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
    let s = scales.find((x) => x.unit === unit);
    if (!s) {
      // alternate the sides so two units each get a clear axis: left, right, left …
      s = { key: `y:${unit}`, unit, side: scales.length % 2 === 0 ? 3 : 1 };
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
  const pad = hi > lo ? (hi - lo) * 0.05 : Math.max(Math.abs(hi) * 0.05, 1);
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
