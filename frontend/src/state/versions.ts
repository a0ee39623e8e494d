// Parameter versions of the machine on screen: the list (reloaded after every parameter
// write), taking one, the baseline, comparing, and rollback onto the trial (Keep / Revert).
import { effect, signal } from "@preact/signals";
import { http } from "../api/http";
import type { ParameterWriteResult, VersionDiff, VersionInfo } from "../api/types";
import { loggedIn } from "./auth";
import { paramsVersion, trial, trialMessage } from "./params";
import { machineId, machineUrl } from "./session";

/** The machine's versions, newest first (null: not loaded yet). */
export const versions = signal<VersionInfo[] | null>(null);
/** Which view of the Parameters workspace is open: the list editor or the versions. */
export const paramView = signal<"list" | "versions">("list");

export const baselineOf = (vs: VersionInfo[] | null) => vs?.find((v) => v.baseline) ?? null;

export async function loadVersions(): Promise<void> {
  if (!machineId.value) return;
  try {
    versions.value = await http.get<VersionInfo[]>(machineUrl("/versions"));
  } catch {
    versions.value = null;
  }
}

export async function takeVersion(name: string, note: string, baseline: boolean): Promise<VersionInfo> {
  const v = await http.post<VersionInfo>(machineUrl("/versions"), { name, note, baseline });
  await loadVersions();
  return v;
}

export async function makeBaseline(id: number): Promise<void> {
  await http.post<VersionInfo>(machineUrl(`/versions/${id}/baseline`), {});
  await loadVersions();
}

export async function deleteVersion(id: number): Promise<void> {
  await http.del<unknown>(machineUrl(`/versions/${id}`));
  await loadVersions();
}

/** `from` and `to`: a version's id, "live", "baseline" or "defaults". */
export async function compare(from: string, to: string): Promise<VersionDiff> {
  return http.get<VersionDiff>(machineUrl(`/versions/diff?${new URLSearchParams({ from, to })}`));
}

/** Write the version's values back and put them on trial, so Revert undoes the rollback. */
export async function rollback(v: VersionInfo): Promise<ParameterWriteResult> {
  const r = await http.post<ParameterWriteResult>(machineUrl(`/versions/${v.id}/rollback`), { comment: "" });
  paramsVersion.value++;
  const first = r.changes[0];
  trial.value = first
    ? { machine: machineId.value, scope: first.scope, target: first.target, applied: r.changes, label: `rollback to '${v.name}'` }
    : null;
  trialMessage.value = r.changes.length ? "" : `No value changed: the parameters already match '${v.name}'.`;
  return r;
}

effect(() => {
  versions.value = null;
  if (loggedIn.value && machineId.value) void loadVersions();
});
