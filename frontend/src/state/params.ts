// Reading parameter lists, the registry's data types, and a version that bumps after every
// write so panels that show parameter-derived things (gear ranges, override limit) reload
// them. The trial (Apply → Keep or Revert) lives here, not in the editor, so it survives
// switching workspaces to test the values.
import { computed, effect, signal } from "@preact/signals";
import { http } from "../api/http";
import type { ParameterChange, ParameterDef, ParameterValue, ParameterWriteResult, Scope } from "../api/types";
import { me } from "./auth";
import { holderKey, standing } from "./control";
import { events } from "./events";
import { machineId, machineUrl, status } from "./session";
import { kept, keptSignal } from "./workspace";

/** One edit: the value, and the version it was read at (refused when someone wrote since;
 * null: no check). */
export interface Change {
  name: string;
  value: number | string;
  base_version: number | null;
}

export const paramsVersion = signal(0);

/** The parameter editor's choices, kept per machine across workspaces: the list shown (its
 * label, "Axis X", "Channel", "Tools"), the search text and the group. */
export const paramListView = kept("params", { list: "Axis X", query: "", group: "" });

export function listUrl(path: string, scope: Scope, target: string | null): string {
  const q = new URLSearchParams({ scope });
  if (target) q.set("target", target);
  return machineUrl(`/parameters${path}?${q}`);
}

export async function loadList(scope: Scope, target: string | null): Promise<ParameterValue[]> {
  return http.get<ParameterValue[]>(listUrl("", scope, target));
}

/** name -> value (numbers only) of a list. */
export async function numbers(scope: Scope, target: string | null): Promise<Map<string, number>> {
  const out = new Map<string, number>();
  for (const p of await loadList(scope, target)) if (typeof p.value === "number") out.set(p.name, p.value);
  return out;
}

/** Data type (UNS32, REAL64, …) of every registry entry by its ID, loaded once. */
export const dtypes = signal<Map<string, string>>(new Map());
/** Every registered parameter (all scopes): where a search finds what the open list lacks. */
export const registryDefs = signal<ParameterDef[]>([]);
let registryLoad: Promise<void> | null = null;
export function loadRegistry(): Promise<void> {
  registryLoad ??= http.get<ParameterDef[]>("/api/parameters").then(
    (defs) => {
      dtypes.value = new Map(defs.map((d) => [d.id, d.dtype]));
      registryDefs.value = defs;
    },
    () => void (registryLoad = null), // try again next time
  );
  return registryLoad;
}

export interface Trial {
  machine: string;
  scope: Scope;
  target: string | null;
  applied: ParameterWriteResult["changes"];
  /** What was applied, when it is not one list's edit (e.g. "rollback to 'as delivered'");
   * each applied change names its own list, so a trial may span several. */
  label?: string;
}

/** Values applied on trial, waiting for Keep or Revert (one trial at a time; a reload of the
 * tab keeps it). */
export const trial = keptSignal<Trial | null>("trial", null);
/** The trial of the machine on screen (another machine's trial waits for its machine). */
export const shownTrial = computed(() => (trial.value?.machine === machineId.value ? trial.value : null));
/** What the last Keep/Revert did (or why Revert failed). */
export const trialMessage = signal("");
/** The last Revert left values waiting for a restart (the trial bar offers it). */
export const revertWaitsForRestart = signal(false);

/** The trial's parameters as they stand now (by scope/target/name), reloaded after every
 * write and every new build: whether a value still waits for its reset or restart. */
export const trialNow = signal<Map<string, ParameterValue>>(new Map());
export const changeKey = (c: { scope: Scope; target?: string | null; name: string }) => `${c.scope}/${c.target ?? ""}/${c.name}`;
effect(() => {
  void paramsVersion.value;
  const t = shownTrial.value;
  trialNow.value = new Map();
  if (!t) return;
  const lists = new Set(t.applied.map((c) => `${c.scope}/${c.target ?? ""}`));
  void Promise.all(
    [...lists].map((l) => {
      const [scope, target] = l.split("/");
      return loadList(scope as Scope, target || null);
    }),
  ).then(
    (rows) => {
      if (shownTrial.peek() !== t) return; // another trial meanwhile
      trialNow.value = new Map(rows.flat().map((p) => [changeKey(p), p]));
    },
    () => undefined, // unknown: the bar shows the trial as applied
  );
});

export async function writeChanges(
  scope: Scope,
  target: string | null,
  changes: Change[],
  comment: string,
): Promise<ParameterWriteResult> {
  return writeAll(
    changes.map((c) => ({ scope, target, name: c.name, value: c.value, base_version: c.base_version })),
    comment,
  );
}

/** One write of values of any lists (all are applied or none). */
export async function writeAll(changes: ParameterChange[], comment: string): Promise<ParameterWriteResult> {
  const r = await http.patch<ParameterWriteResult>(machineUrl("/parameters"), { changes, comment });
  paramsVersion.value++;
  return r;
}

/** A class seat moved on to its next exercise: its machine powered on afresh with that
 * exercise's parameters, so the values on trial of the last one went with it. */
export function dropTrialOf(machine: string): void {
  if (trial.peek()?.machine !== machine) return;
  trial.value = null;
  trialMessage.value = "The next exercise began: the values on trial of the last one went with it.";
}

export function keepTrial(): void {
  const t = trial.peek();
  trial.value = null;
  const n = t?.applied.length ?? 0;
  trialMessage.value = `✓ Kept ${n} value${n === 1 ? "" : "s"}: they stay as the machine's parameters.`;
}

/** Write the old values back, unless someone wrote over the trial's values meanwhile (their
 * value is not ours to revert: its version changed; a reset or restart taking our value in
 * leaves the version); the trial stays when that is refused. Each change goes back to its
 * own list (a rollback's trial spans several). */
export async function revertTrial(): Promise<void> {
  const t = trial.value;
  if (!t) return;
  type Applied = Trial["applied"][number];
  const key = (c: Applied) => `${c.scope}/${c.target ?? ""}`;
  try {
    const lists = new Map<string, Map<string, ParameterValue>>();
    for (const c of t.applied) {
      if (!lists.has(key(c))) lists.set(key(c), new Map((await loadList(c.scope, c.target ?? null)).map((p) => [p.name, p])));
    }
    const now = (c: Applied) => lists.get(key(c))?.get(c.name);
    const named = (c: Applied) => (lists.size > 1 && c.target ? `${c.target}: ${c.name}` : c.name);
    const changed = t.applied.filter((c) => {
      const p = now(c);
      return p && p.version !== c.version;
    });
    if (changed.length) {
      trialMessage.value = `Revert refused: ${changed.map(named).join(", ")} changed by someone else since the trial (reload the list).`;
      return;
    }
    // a value that was at its default (old null: never written) goes back to the default
    const back: ParameterChange[] = [];
    for (const c of t.applied) {
      const value = c.old ?? now(c)?.default ?? null;
      if (value !== null) back.push({ scope: c.scope, target: c.target, name: c.name, value, base_version: c.version });
    }
    const r = await writeAll(back, "editor: revert");
    trial.value = null;
    // a value the restart had taken in goes back as a pending one: it needs a restart again
    const waiting = r.changes.filter((c) => c.pending);
    revertWaitsForRestart.value = waiting.some((c) => c.effect === "restart");
    trialMessage.value =
      `Reverted ${back.length} value(s).` +
      (waiting.length ? ` Back in force at the next ${waiting.map((c) => `${c.effect}: ${c.name} ${c.new}`).join(", ")}.` : "");
  } catch (e) {
    trialMessage.value = `Revert refused: ${e instanceof Error ? e.message : String(e)}`;
  }
}

function clearTrialMessage(): void {
  trialMessage.value = "";
  revertWaitsForRestart.value = false;
}

effect(() => {
  void machineId.value; // a message belongs to the machine it was about
  clearTrialMessage();
});

effect(() => {
  // ... and to its holder at the time: "Kept." is old news to the next one. A tab that took the
  // free machine by applying keeps its own news (that holder change may show after its Keep).
  void holderKey.value;
  if (standing.peek() !== "mine") clearTrialMessage();
});

effect(() => {
  // a trial belongs to the session that applied it: the next user must not see its Keep/Revert
  // (null: logged out; undefined while a reload asks who is logged in: the trial stays)
  if (me.value !== null) return;
  trial.value = null;
  trialMessage.value = "";
});

/** The build of the machine on screen (status.simulation.epoch): a restart by anyone, a
 * restore or a rebuild after its worker died brings a new one, with the values that waited
 * for it in force. */
const build = computed(() => {
  const st = status.value;
  return st ? `${st.id}/${st.simulation.epoch}` : null;
});
let lastBuild: string | null = null;
effect(() => {
  const b = build.value;
  if (b === null) return; // between machines, or before the first status
  const same = lastBuild !== null && b.split("/")[0] === lastBuild.split("/")[0];
  if (same && b !== lastBuild) {
    paramsVersion.value = paramsVersion.peek() + 1; // every view reloads
    revertWaitsForRestart.value = false; // the restart took them in
  }
  lastBuild = b;
});

// A CNC reset (by anyone, on any screen) takes in the values that waited for it: every view
// reloads, so the trial bar no longer says "(at reset)" of a value in force since.
const EV_RESET = 14; // nc_sim/errors.py Code.EV_RESET
const newestReset = computed(() => {
  const resets = events.value.filter((e) => e.code === EV_RESET);
  return resets.length ? `${machineId.value}/${resets[resets.length - 1].cycle}` : `${machineId.value}/none`;
});
let lastReset: string | null = null;
effect(() => {
  const r = newestReset.value;
  const same = lastReset !== null && r.split("/")[0] === lastReset.split("/")[0];
  if (same && r !== lastReset) paramsVersion.value = paramsVersion.peek() + 1;
  lastReset = r;
});
