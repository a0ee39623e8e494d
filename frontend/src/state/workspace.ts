// Workspace state kept for the session: App mounts only the workspace on screen, so what a
// panel keeps in its own component state dies with every tab switch. A `Kept` value lives
// here instead, per machine (a jog feed is a machine's, not the page's), mirrored to
// sessionStorage so that a reload of the tab keeps it too; logging out forgets it all.
import { effect, signal, type Signal } from "@preact/signals";
import { me } from "./auth";
import { machineId } from "./session";

const PREFIX = "inbetrieb.ws.";
const all: Signal<Record<string, unknown>>[] = [];
const forgets: (() => void)[] = [];

/** A value per machine that outlives the panel showing it. */
export interface Kept<T> {
  /** The current machine's value (its initial one until set). */
  readonly value: T;
  /** Set some of the current machine's value. */
  patch(p: Partial<T>): void;
}

function load(name: string): Record<string, unknown> {
  try {
    const raw = sessionStorage.getItem(PREFIX + name);
    return raw ? (JSON.parse(raw) as Record<string, unknown>) : {};
  } catch {
    return {}; // a broken entry: start afresh
  }
}

/** A kept value named `name` (its sessionStorage key), `initial` until set. */
export function kept<T extends object>(name: string, initial: T): Kept<T> {
  const byMachine = signal<Record<string, unknown>>(load(name));
  all.push(byMachine);
  return {
    get value(): T {
      return { ...initial, ...(byMachine.value[machineId.value] as Partial<T> | undefined) };
    },
    patch(p: Partial<T>): void {
      const mid = machineId.value;
      if (!mid) return;
      const now = byMachine.value[mid] as Partial<T> | undefined;
      byMachine.value = { ...byMachine.value, [mid]: { ...now, ...p } };
      try {
        sessionStorage.setItem(PREFIX + name, JSON.stringify(byMachine.value));
      } catch {
        /* storage full or refused: the page keeps it still */
      }
    },
  };
}

/** A value of the session (one for all machines, e.g. the one trial of parameters) mirrored
 * to sessionStorage under `name`: a reload of the tab keeps it, logging out forgets it. */
export function keptSignal<T>(name: string, initial: T): Signal<T> {
  let stored: T = initial;
  try {
    const raw = sessionStorage.getItem(PREFIX + name);
    if (raw) stored = JSON.parse(raw) as T;
  } catch {
    /* a broken entry: start afresh */
  }
  const s = signal<T>(stored);
  forgets.push(() => void (s.value = initial));
  effect(() => {
    try {
      sessionStorage.setItem(PREFIX + name, JSON.stringify(s.value));
    } catch {
      /* storage full or refused: the page keeps it still */
    }
  });
  return s;
}

effect(() => {
  // the next user of this tab starts from the defaults (null: nobody; undefined: not known yet)
  if (me.value !== null) return;
  for (const s of all) s.value = {};
  for (const forget of forgets) forget();
  for (const k of Object.keys(sessionStorage)) if (k.startsWith(PREFIX)) sessionStorage.removeItem(k);
});
