// What the console shows besides the grid: one seat's detail (debrief), the fault form.
import { signal } from "@preact/signals";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";

/** The seat whose detail shows (its number), or null. */
export const detailSeat = signal<number | null>(null);

/** What the console's main area shows: the open class, the roster, or the exercises. */
export const consoleView = signal<"class" | "roster" | "exercises">("class");

/** The fault form, open for these seats (an empty list: the whole class), or null. */
export const faultFor = signal<number[] | null>(null);

/** The refusal of the newest console action (freeze, message, inject ...), until the next. */
export const actionRefusal = signal<Refusal | null>(null);

/** Run a console action; its refusal (or nothing) shows under the grid's bar. */
export async function act(what: () => Promise<unknown>): Promise<boolean> {
  try {
    await what();
    actionRefusal.value = null;
    return true;
  } catch (e) {
    actionRefusal.value = e instanceof ApiError ? e.refusal : { message: String(e), problems: [] };
    return false;
  }
}
