// The event log: job errors and information events, as the socket sends them (the newest
// ones when it connects, then each new one).
import { computed, effect, signal } from "@preact/signals";
import type { JobError } from "../api/types";
import { machineId, status } from "./session";

const MAX_EVENTS = 500;
export const events = signal<JobError[]>([]);
const seen = new Set<string>();
/** Keys of the active errors the operator acknowledged (the banner hides them). */
export const acknowledged = signal<ReadonlySet<string>>(new Set());

export const keyOf = (e: JobError) => `${e.cycle}:${e.code}:${e.axis}`;

/** The machine was rebuilt (its worker died) or restored from a snapshot: its time starts
 * again or goes back, so the log starts again too, with the notice as its first entry. */
export function restartLog(message: string): void {
  events.value = [];
  seen.clear();
  acknowledged.value = new Set();
  addEvents([
    { cycle: 0, t_s: 0, axis: "", code: 0, message, error: false, seq: null, m: null, gear: null, line: null, column: null, signal: null },
  ]);
}

export function addEvents(list: JobError[]): void {
  const fresh = list.filter((e) => !seen.has(keyOf(e)));
  if (!fresh.length) return;
  fresh.forEach((e) => seen.add(keyOf(e)));
  const all = [...events.value, ...fresh].sort((a, b) => a.cycle - b.cycle);
  events.value = all.slice(-MAX_EVENTS);
}

/** The job errors still active (the pushed status has one per axis, an emergency stop once)
 * and not acknowledged, newest first: the banner shows them. A reset clears them there; the
 * log (Events panel) keeps their history. */
export const bannerErrors = computed(() =>
  (status.value?.job_errors ?? []).filter((e) => !acknowledged.value.has(keyOf(e))).sort((a, b) => b.cycle - a.cycle),
);

export function acknowledgeBanner(): void {
  acknowledged.value = new Set([...acknowledged.value, ...bannerErrors.value.map(keyOf)]);
}

effect(() => {
  void machineId.value; // a new machine: a new log
  events.value = [];
  seen.clear();
  acknowledged.value = new Set();
});
