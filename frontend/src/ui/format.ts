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
