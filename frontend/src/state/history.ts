// The machine's history as it grows: the entries the socket pushes while the page is open
// (the History panel loads older ones by REST and merges these in).
import { effect, signal } from "@preact/signals";
import type { HistoryEntry } from "../api/types";
import { machineId } from "./session";

const KEPT = 500;
/** New entries since the page connected, oldest first. */
export const liveHistory = signal<HistoryEntry[]>([]);

export function addHistory(entries: HistoryEntry[]): void {
  liveHistory.value = [...liveHistory.value, ...entries].slice(-KEPT);
}

effect(() => {
  void machineId.value; // another machine: another history
  liveHistory.value = [];
});
