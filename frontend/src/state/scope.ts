// The scope: its status (polled while the Scope workspace is open), the setup being edited
// (kept per machine), the trace on screen and the one overlaid, the measurement's channel and
// band, and the trace library.
import { computed, effect, signal } from "@preact/signals";
import { http } from "../api/http";
import type { RecordingInfo, ScopeSetup, ScopeStatus, TraceDetail, TraceInfo } from "../api/types";
import { machineId, machineUrl } from "./session";
import { decodeFrame } from "./telemetry";
import { kept } from "./workspace";

export const SCOPE_PERIOD_MS = 250;
export const MAX_CHANNELS = 16;
export const MAX_DRIVE_S = 2; // a drive-rate capture (the API's MAX_DRIVE_LENGTH_S)
export const DEFAULT_CHANNELS = ["S1.speed_cmd_rpm", "S1.speed_act_rpm", "S1.pos_act_deg", "S1.lag_deg"];

export const scopeStatus = signal<ScopeStatus | null>(null);
export const library = signal<TraceInfo[]>([]);
export const shownId = signal<string>(""); // trace on screen ("" = none)
export const overlayId = signal<string>(""); // trace drawn dashed behind it
export const followNewest = signal(true); // show each new capture as it completes

/** A trace ready to draw: times from the trigger (s) and one array per channel. */
export interface LoadedTrace {
  detail: TraceDetail;
  t: Float64Array;
  channels: Map<string, Float64Array>;
}

const DEFAULT_SETUP: ScopeSetup = {
  channels: DEFAULT_CHANNELS,
  rate: "nc",
  length_s: 1,
  pretrigger_pct: 20,
  mode: "single",
  trigger: { type: "event", event: "m_start", axis: "S1", m: 19 },
  take_over: false,
};

const key = () => `inbetrieb.scope.${machineId.value}`;

/** The measurements' channel ("" until chosen: the trace's first float channel) and the
 * settling band, % — kept across workspaces. */
export const measure = kept("measure", { channel: "", band: 2 });

function loadDraft(): ScopeSetup {
  try {
    const raw = localStorage.getItem(key());
    if (raw) return { ...DEFAULT_SETUP, ...(JSON.parse(raw) as ScopeSetup) };
  } catch {
    /* a broken entry: start from the default */
  }
  return DEFAULT_SETUP;
}

const drafts = signal<Record<string, ScopeSetup>>({});
/** The setup being edited for the machine on screen (the one last armed or edited). */
export const scopeDraft = computed(() => drafts.value[machineId.value] ?? loadDraft());

/** Edit the setup (kept, and stored for the next session). */
export function saveDraft(s: ScopeSetup): void {
  drafts.value = { ...drafts.value, [machineId.value]: s };
  localStorage.setItem(key(), JSON.stringify(s));
}

let lastNewest = "";

export async function pollScope(): Promise<void> {
  const asked = machineId.value;
  if (!asked) return;
  try {
    const st = await http.get<ScopeStatus>(machineUrl("/scope"));
    // an answer about the machine shown before a switch would show its capture on this one
    if (machineId.value !== asked) return;
    scopeStatus.value = st;
    const newest = st.captures[0]?.id ?? "";
    if (newest && newest !== lastNewest && followNewest.value) shownId.value = newest;
    lastNewest = newest;
  } catch {
    /* the status poll reports the connection */
  }
}

/** Arm with this setup; `takeOver` another person's scope that still records (the holder
 * of control, instructors and admins may: the service refuses it otherwise). */
export async function arm(setup: ScopeSetup, takeOver = false): Promise<void> {
  saveDraft({ ...setup, take_over: false });
  scopeStatus.value = await http.put<ScopeStatus>(machineUrl("/scope"), { ...setup, take_over: takeOver });
}

export async function force(): Promise<void> {
  scopeStatus.value = await http.post<ScopeStatus>(machineUrl("/scope/force"), {});
}

export async function stop(): Promise<void> {
  scopeStatus.value = await http.post<ScopeStatus>(machineUrl("/scope/stop"), {});
}

export async function startRecording(signals: string[]): Promise<RecordingInfo> {
  return http.post<RecordingInfo>(machineUrl("/recording"), { signals });
}

export async function stopRecording(): Promise<RecordingInfo> {
  return http.del<RecordingInfo>(machineUrl("/recording"));
}

export async function refreshLibrary(): Promise<void> {
  library.value = await http.get<TraceInfo[]>("/api/traces");
}

const cache = new Map<string, LoadedTrace>();

/** A trace's description and samples (cached; a stored trace's name is read fresh). */
export async function loadTrace(id: string): Promise<LoadedTrace> {
  const detail = await http.get<TraceDetail>(`/api/traces/${id}`);
  const hit = cache.get(id);
  if (hit) return { ...hit, detail };
  const f = decodeFrame(await http.bytes(`/api/traces/${id}/data`));
  if (!f) throw new Error(`trace ${id}: not a sample frame`);
  const { header: h, data } = f;
  const ref = detail.trigger_cycle ?? detail.first_cycle;
  const t = new Float64Array(h.count);
  for (let k = 0; k < h.count; k++) t[k] = (h.first_cycle + k - ref) * h.cycle_s;
  const channels = new Map<string, Float64Array>();
  h.signals.forEach((name, i) => channels.set(name, data.subarray(i * h.count, (i + 1) * h.count)));
  const loaded = { detail, t, channels };
  cache.set(id, loaded);
  if (cache.size > 8) cache.delete(cache.keys().next().value as string);
  return loaded;
}

/** The newest window of a rolling scope, times relative to its newest sample. */
export interface RollData {
  t: Float64Array;
  channels: Map<string, Float64Array>;
  lastCycle: number;
  stride: number;
}

export async function loadRoll(maxPoints: number): Promise<RollData | null> {
  let buf: ArrayBuffer;
  try {
    buf = await http.bytes(machineUrl(`/scope/roll?max_points=${Math.max(100, Math.round(maxPoints))}`));
  } catch {
    return null; // the next tick asks again
  }
  const f = decodeFrame(buf);
  if (!f) return null;
  const { header: h, data } = f;
  const last = h.first_cycle + (h.count - 1) * h.stride;
  const t = new Float64Array(h.count);
  for (let k = 0; k < h.count; k++) t[k] = (h.first_cycle + k * h.stride - last) * h.cycle_s;
  const channels = new Map<string, Float64Array>();
  h.signals.forEach((name, i) => channels.set(name, data.subarray(i * h.count, (i + 1) * h.count)));
  return { t, channels, lastCycle: last, stride: h.stride };
}

/** A trace the address names (`#machine/scope/<trace>`): shown once its machine is. */
export const linkedTrace = { id: "" };

effect(() => {
  // another machine: its own scope and captures (another's stay in the trace library, named
  // by their machine); back on this one, its newest capture shows again, unless the address
  // names a trace
  const mid = machineId.value;
  const linked = mid ? linkedTrace.id : "";
  if (linked) linkedTrace.id = "";
  scopeStatus.value = null;
  shownId.value = linked;
  overlayId.value = "";
  followNewest.value = !linked;
  lastNewest = "";
});
