// The commissioning assistants (api/assist.py): run one on a copy of the machine, and apply
// its proposal through the parameter write the editor uses, on trial (Keep / Revert).
import { computed, signal } from "@preact/signals";
import { http } from "../api/http";
import type { AssistantInfo, AssistChange, AssistProgress, AssistResult, ParameterWriteResult, Scope } from "../api/types";
import { type Change, loadList, trial, trialMessage, writeChanges } from "./params";
import { machineId, machineUrl, status } from "./session";

/** Where a run happens: on a copy of the machine in simulated time, or on the machine. */
export type Where = "copy" | "machine";

/** Every assistant as the service describes it (title, section, where it runs, the schema
 * its form is made from), read once per page. */
export const catalogue = signal<AssistantInfo[]>([]);
let asked: Promise<void> | null = null;
export function loadCatalogue(): Promise<void> {
  asked ??= http.get<AssistantInfo[]>("/api/assistants").then(
    (list) => void (catalogue.value = list),
    () => void (asked = null), // asked again by the next panel that needs it
  );
  return asked;
}

/** "multi_gain by experiment (004 §3.6.2)": an assistant by its title (its name when the
 * service no longer knows it). */
export function titleOf(name: string): string {
  const a = catalogue.value.find((x) => x.name === name);
  return a ? `${a.title} (${a.section})` : name;
}

/** Run an assistant with the body its request schema describes; rejects with the service's
 * refusal (ApiError: 422 says which input, 409 a live run cancelled or another running). */
export function runAssistant(name: string, body: object, where: Where): Promise<AssistResult> {
  return http.post<AssistResult>(machineUrl(where === "machine" ? `/assist/live/${name}` : `/assist/${name}`), body);
}

/** The assistant running live on the machine now (anyone's), from the pushed status. */
export const liveRun = computed<AssistProgress | null>(() => status.value?.assist ?? null);

/** End the live run now (any operator, like the E-stop). */
export function cancelLive(): Promise<void> {
  return http.post<void>(machineUrl("/assist/live/cancel"), { why: "cancelled in the HMI" });
}

/** The value of figure `name`, or null. */
export const figure = (r: AssistResult, name: string): number | null => r.figures.find((f) => f.name === name)?.value ?? null;

/** A change's list: an axis by name, or the channel. */
function listOf(target: string): { scope: Scope; target: string | null } {
  return target === "channel" ? { scope: "channel", target: null } : { scope: "axis", target };
}

/** Write the proposed changes (one list) and put them on trial. Each is written against the
 * version read now, and only when its value is still the one the run measured with: a value
 * changed since the run makes the proposal stale (run again), not something to overwrite. */
export async function applyProposal(assistant: string, changes: AssistChange[]): Promise<ParameterWriteResult> {
  const targets = [...new Set(changes.map((c) => c.target))];
  if (targets.length !== 1) throw new Error(`the proposal spans ${targets.join(", ")}: one list at a time`);
  const { scope, target } = listOf(targets[0]);
  const now = new Map((await loadList(scope, target)).map((p) => [p.name, p]));
  const writes: Change[] = changes.map((c) => {
    const p = now.get(c.parameter);
    if (!p) throw new Error(`${c.parameter} is not in the list of ${targets[0]}`);
    if (String(p.pending ?? p.value) !== String(c.before))
      throw new Error(`${c.parameter} is ${String(p.pending ?? p.value)} now, not ${String(c.before)} as in the run: run it again`);
    return { name: c.parameter, value: c.after, base_version: p.version };
  });
  const r = await writeChanges(scope, target, writes, `assistant ${assistant}: apply (trial)`);
  trial.value = r.changes.length ? { machine: machineId.value, scope, target, applied: r.changes } : null;
  trialMessage.value = "";
  return r;
}

/** Power the machine off and on: values that take effect at restart (the signs of 004 §3.5)
 * come into force. Needs control, like a command. */
export function restartMachine(): Promise<unknown> {
  return http.post<unknown>(machineUrl("/restart"), {});
}
