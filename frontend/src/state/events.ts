// The event log: job errors and information events, as the socket sends them (the newest
// ones when it connects, then each new one).
import { computed, effect, signal } from "@preact/signals";
import type { JobError } from "../api/types";
import { machineId } from "./session";

const MAX_EVENTS = 500;
export const events = signal<JobError[]>([]);
const seen = new Set<string>();
/** Key of the newest error the operator acknowledged (banner hidden up to it). */
export const acknowledged = signal("");

export const keyOf = (e: JobError) => `${e.cycle}:${e.code}:${e.axis}`;

/** The machine was rebuilt (its worker died): its time and log start again, so the log
 * starts again too, with the notice as its first entry. */
export function restartLog(message: string): void {
  events.value = [];
  seen.clear();
  acknowledged.value = "";
  addEvents([{ cycle: 0, t_s: 0, axis: "", code: 0, message, error: false, seq: null, m: null, gear: null }]);
}

export function addEvents(list: JobError[]): void {
  const fresh = list.filter((e) => !seen.has(keyOf(e)));
  if (!fresh.length) return;
  fresh.forEach((e) => seen.add(keyOf(e)));
  const all = [...events.value, ...fresh].sort((a, b) => a.cycle - b.cycle);
  events.value = all.slice(-MAX_EVENTS);
}

/** The newest job error not yet acknowledged: the banner shows it. */
export const bannerError = computed(() => {
  const errs = events.value.filter((e) => e.error);
  const last = errs[errs.length - 1];
  return last && keyOf(last) !== acknowledged.value ? last : null;
});

export function acknowledgeBanner(): void {
  const e = bannerError.value;
  if (e) acknowledged.value = keyOf(e);
}

effect(() => {
  void machineId.value; // a new machine: a new log
  events.value = [];
  seen.clear();
  acknowledged.value = "";
});
