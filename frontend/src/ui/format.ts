/** Fixed decimals, with a real minus sign and "—" for missing values. */
export function fmt(v: number | null | undefined, decimals = 3): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  const s = Math.abs(v).toFixed(decimals);
  return v < 0 && Number(s) !== 0 ? `−${s}` : s;
}

/** A value with its unit, joined by a no-break space so a narrow line never leaves the unit
 * on a line of its own ("100.0 %", "0.500 s"). */
export function qty(v: number | null | undefined, decimals: number, unit: string): string {
  return unit ? `${fmt(v, decimals)}\u00a0${unit}` : fmt(v, decimals);
}

/** A spindle's speed reads in rpm, except as the rotary axis C (°/min, like any rotary axis). */
export const velUnit = (unit: string, kind: string, spindleMode?: string | null) =>
  kind === "spindle" && spindleMode !== "rotary" ? "rpm" : `${unit}/min`;

/** Axis tick labels: as many decimals as the tick spacing needs (so neighbouring ticks never
 * read the same), powers of ten for very small or large spacings, and never "−0". */
export function tickLabels(splits: number[]): string[] {
  const steps = splits.slice(1).map((v, i) => Math.abs(v - splits[i])).filter((d) => d > 0);
  const step = steps.length ? Math.min(...steps) : Math.abs(splits[0] ?? 0) || 1;
  const mag = Math.floor(Math.log10(step));
  const lead = step / 10 ** mag; // 1, 2, 2.5, 5: a half step needs one digit more
  const extra = Math.abs(lead - Math.round(lead)) > 1e-6 ? 1 : 0;
  const big = Math.max(...splits.map((v) => Math.abs(v)));
  // a tick within float error of zero is zero (uPlot builds splits by adding steps)
  const zero = (v: number) => Math.abs(v) < step * 1e-9;
  if (mag < -4 || big >= 1e7) {
    // mantissa digits enough to tell ticks `step` apart at the largest magnitude
    const digits = Math.max(1, Math.min(15, Math.floor(Math.log10(big || step)) - mag + 1 + extra));
    return splits.map((v) => (zero(v) ? "0" : v.toExponential(digits - 1).replace(/-/g, "−")));
  }
  const decimals = Math.max(0, -mag + extra);
  return splits.map((v) => (zero(v) ? "0" : fmt(v, decimals)));
}

/** A parameter's value in the HMI's unit (the list value × the API's eng_factor, in its
 * eng_unit: mm/min, rpm, %, 1/s …): six significant digits, no trailing zeros, so 20 1/s,
 * 100 % and 19999.98 mm/min read as they are. */
export function engQty(v: number | null | undefined, unit: string): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  const s = String(+v.toPrecision(6));
  return qty(Number(s), Math.max(0, (s.split(".")[1] ?? "").length), unit);
}

/** multi_gain as the manual defines it [004 §3.6.2]: multi_gain_z / multi_gain_n, the D/A
 * digits at 1 m/min (linear) or 1000 °/min (rotary axes and spindles). */
export function multiGainText(z: number, n: number, linear: boolean): string {
  return `multi_gain ${engQty(z / n, "")} digits per ${linear ? "1 m/min" : "1000 °/min"}`;
}

/** A gear stage by its three names [000 §2.8.2]: the M function that selects it, its number
 * (1…6) and its axis gear record, "M42 · gear 3 · getriebe[2]". `m` false: an axis without
 * gear change (no M function). */
export function gearName(gear: number, m = true): string {
  return `${m ? `M${39 + gear} · ` : ""}gear ${gear} · getriebe[${gear - 1}]`;
}

/** Round tick values from 0 to at least `top` (1, 2 or 5 × 10^k apart, about `count`). */
export function niceTicks(top: number, count = 5): number[] {
  if (!(top > 0)) return [0];
  const raw = top / count;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((f) => f * mag).find((s) => s >= raw) ?? 10 * mag;
  const out: number[] = [];
  const n = Math.ceil(top / step - 1e-9); // the last tick at or above the top
  for (let k = 0; k <= n; k++) out.push(k * step);
  return out;
}
