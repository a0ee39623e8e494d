// Reading parameter lists, and a version that bumps after every write so panels that show
// parameter-derived things (gear ranges, override limit) reload them.
import { signal } from "@preact/signals";
import { http } from "../api/http";
import type { ParameterValue, Scope } from "../api/types";
import { machineUrl } from "./session";

export const paramsVersion = signal(0);

export function listUrl(path: string, scope: Scope, target: string | null): string {
  const q = new URLSearchParams({ scope });
  if (target) q.set("target", target);
  return machineUrl(`/parameters${path}?${q}`);
}

export function loadList(scope: Scope, target: string | null): Promise<ParameterValue[]> {
  return http.get<ParameterValue[]>(listUrl("", scope, target));
}

/** name -> value (numbers only) of a list. */
export async function numbers(scope: Scope, target: string | null): Promise<Map<string, number>> {
  const out = new Map<string, number>();
  for (const p of await loadList(scope, target)) if (typeof p.value === "number") out.set(p.name, p.value);
  return out;
}
