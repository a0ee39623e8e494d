// A class's presentation: the instructor shows a machine to every seat (`me.watches`); its
// students may switch to it and watch, read-only, and back. A "present" notice on the seat
// says it began or ended; while watching, the service is asked now and then whether it still
// goes on (the notice of its end goes to the seats, not to the machine watched).
import { computed } from "@preact/signals";
import { http } from "../api/http";
import type { MachineSummary } from "../api/types";
import { loadMe, me } from "./auth";
import { machineId, machines, selectMachine } from "./session";

const POLL_MS = 5000;

/** The machine on screen is the one the instructor presents (not the student's seat). */
export const watching = computed(() => !!me.value?.watches && machineId.value === me.value.watches);

/** The student's own seat machine (the list marks it). */
export const ownSeat = computed(() => machines.value.find((m) => m.seat)?.id ?? "");

/** Who may see what changed: read `me` and the machine list again; a student watching a
 * presentation that ended goes back to their seat. */
export async function presentationChanged(): Promise<void> {
  await loadMe();
  const list = await http.get<MachineSummary[]>("/api/machines");
  machines.value = list;
  if (!list.some((m) => m.id === machineId.value)) selectMachine(list.find((m) => m.seat)?.id ?? list[0]?.id ?? "");
}

setInterval(() => {
  if (watching.value) void presentationChanged().catch(() => undefined);
}, POLL_MS);
