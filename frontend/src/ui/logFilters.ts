// What the History and the service's audit trail share: their time-range presets, how long
// typing must pause before a text filter applies, and how a row's wall time reads.

/** Time range presets: how far back, in seconds (0: everything). */
export const TIME_RANGES: { label: string; back_s: number }[] = [
  { label: "all time", back_s: 0 },
  { label: "last 15 min", back_s: 15 * 60 },
  { label: "last hour", back_s: 3600 },
  { label: "last 24 h", back_s: 24 * 3600 },
  { label: "last 7 days", back_s: 7 * 24 * 3600 },
];

export const TYPING_MS = 300; // the user and text filters apply once typing pauses this long

/** A Unix time as this computer's date and time. */
export function wallTime(t: number): string {
  const d = new Date(t * 1000);
  return `${d.toLocaleDateString()} ${d.toLocaleTimeString()}`;
}
