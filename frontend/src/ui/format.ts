/** Fixed decimals, with a real minus sign and "—" for missing values. */
export function fmt(v: number | null | undefined, decimals = 3): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "—";
  const s = Math.abs(v).toFixed(decimals);
  return v < 0 && Number(s) !== 0 ? `−${s}` : s;
}

export const velUnit = (unit: string, kind: string) => (kind === "spindle" ? "rpm" : `${unit}/min`);
