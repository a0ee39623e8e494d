// Deep links: the URL names the machine, the workspace and a trace, so a moment can be pasted
// into a ticket: `#<machine>/<workspace>` (`#demo/history`), `#<machine>/scope/<trace>` (that
// trace open in the scope), `#bundle/<id>[/<trace>]` (an opened bundle's page, one of its
// traces on it). The address follows what is on screen without adding to the browser's
// history at each tab.
import { effect, signal } from "@preact/signals";
import { followNewest, linkedTrace, shownId } from "./scope";
import { machineId, selectMachine } from "./session";

export const TABS = ["Exercise", "Operate", "Program", "Plots", "Scope", "Parameters", "Commissioning", "Drive tuning", "Service", "HLI / PLC", "History", "Fleet"] as const;
export type Tab = (typeof TABS)[number];

const slug = (t: Tab) => t.toLowerCase().replace(/[^a-z0-9]+/g, "-");
const bySlug = new Map(TABS.map((t) => [slug(t), t]));

/** The parts of the address: machine, workspace, trace ("" where it names none). */
export function parseHash(hash: string): { machine: string; tab: Tab | null; trace: string } {
  const [machine = "", ws = "", trace = ""] = decodeURIComponent(hash.replace(/^#/, "")).split("/");
  return { machine, tab: bySlug.get(ws) ?? null, trace: bySlug.get(ws) === "Scope" ? trace : "" };
}

/** An opened diagnostic bundle on its own page (`#bundle/<id>[/<trace>]`), not a live machine. */
export interface BundlePage {
  id: string;
  trace: string;
}
const BUNDLE_HASH = /^#bundle\/([0-9a-f]{12})(?:\/([0-9a-f]+))?/;
function parseBundle(hash: string): BundlePage | null {
  const m = hash.match(BUNDLE_HASH);
  return m ? { id: m[1], trace: m[2] ?? "" } : null;
}
/** The bundle on screen (null: the live HMI). */
export const bundlePage = signal<BundlePage | null>(parseBundle(location.hash));

/** Show an opened bundle's page (trace: one of its alarm traces on screen). */
export function openBundle(id: string, trace = ""): void {
  bundlePage.value = { id, trace };
  history.pushState(null, "", `#bundle/${id}${trace ? `/${trace}` : ""}`);
}

/** One of the bundle's traces on its page (the address names it). */
export function showBundleTrace(trace: string): void {
  const page = bundlePage.value;
  if (!page) return;
  bundlePage.value = { ...page, trace };
  history.replaceState(null, "", `#bundle/${page.id}${trace ? `/${trace}` : ""}`);
}

/** Back from a bundle to the live machine. */
export function closeBundle(): void {
  bundlePage.value = null; // the effect below writes the machine's address
}

const first = parseHash(location.hash);
/** The workspace on screen. */
export const tab = signal<Tab>(first.tab ?? "Operate");
linkedTrace.id = first.trace; // shown once the machine is (state/scope.ts)

/** An address pasted into this tab: its machine, workspace and trace. */
window.addEventListener("hashchange", () => {
  bundlePage.value = parseBundle(location.hash);
  const to = parseHash(location.hash);
  if (bundlePage.value || !to.machine || location.hash.startsWith("#classes")) return;
  if (to.machine !== machineId.value) {
    linkedTrace.id = to.trace;
    selectMachine(to.machine);
  } else if (to.trace && to.trace !== shownId.value) {
    followNewest.value = false;
    shownId.value = to.trace;
  }
  if (to.tab) tab.value = to.tab;
});

/** The address of what is on screen, for a ticket. */
export function hereUrl(): string {
  return `${location.origin}${location.pathname}${location.search}${location.hash}`;
}

/** Show a trace of the library in the scope. */
export function openTrace(id: string): void {
  followNewest.value = false;
  shownId.value = id;
  tab.value = "Scope";
}

effect(() => {
  const mid = machineId.value;
  if (!mid || bundlePage.value || location.hash.startsWith("#classes")) return;
  const trace = tab.value === "Scope" && !followNewest.value && shownId.value ? `/${shownId.value}` : "";
  const next = `#${encodeURIComponent(mid)}/${slug(tab.value)}${trace}`;
  if (location.hash !== next) history.replaceState(null, "", next);
});
