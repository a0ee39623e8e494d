// The event log: job errors and information events, as the socket sends them (the newest
// ones when it connects, then each new one).
import { computed, effect, signal } from "@preact/signals";
import type { JobError } from "../api/types";
import { machineId, status } from "./session";

const MAX_EVENTS = 500;
export const events = signal<JobError[]>([]);
const seen = new Set<string>();
/** Keys of the active errors the operator dismissed (the banner hides them). */
export const dismissed = signal<ReadonlySet<string>>(new Set());

export const keyOf = (e: JobError) => `${e.cycle}:${e.code}:${e.axis}`;

/** The machine was powered on again (rebuilt, the service restarted) or restored from a
 * snapshot: its time starts again or goes back, so the log starts again too. */
export function restartLog(): void {
  events.value = [];
  seen.clear();
  dismissed.value = new Set();
}

export function addEvents(list: JobError[]): void {
  const fresh = list.filter((e) => !seen.has(keyOf(e)));
  if (!fresh.length) return;
  fresh.forEach((e) => seen.add(keyOf(e)));
  const all = [...events.value, ...fresh].sort((a, b) => a.cycle - b.cycle);
  events.value = all.slice(-MAX_EVENTS);
}

/** The job errors still active (the pushed status has one per axis, an emergency stop once)
 * and not dismissed, oldest first: the banner shows the first as the cause. Dismissing only hides them here
 * (the NC is not told: the axis stays in error); a reset clears them. The log (Events panel)
 * keeps their history. */
export const bannerErrors = computed(() =>
  (status.value?.job_errors ?? []).filter((e) => !dismissed.value.has(keyOf(e))).sort((a, b) => a.cycle - b.cycle),
);

/** Hide the banner's errors (they stay active until a reset). */
export function dismissBanner(): void {
  dismissed.value = new Set([...dismissed.value, ...bannerErrors.value.map(keyOf)]);
}

effect(() => {
  void machineId.value; // a new machine: a new log
  events.value = [];
  seen.clear();
  dismissed.value = new Set();
});
