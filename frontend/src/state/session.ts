// The session: which machine, its status polled ~10×/s, the service's loop health, and the one
// way commands are sent.
import { computed, signal } from "@preact/signals";
import { ApiError, http } from "../api/http";
import type { Command, CommandResult, MachineStatus, MachineSummary, ServiceStatus } from "../api/types";

export type Connection = "connecting" | "online" | "lost";

export const machines = signal<MachineSummary[]>([]);
export const machineId = signal<string>("");
export const status = signal<MachineStatus | null>(null);
export const service = signal<ServiceStatus | null>(null);
/** Status polling reachable; the telemetry socket reports its own state. */
export const polling = signal<Connection>("connecting");
export const socket = signal<Connection>("connecting");
export const connection = computed<Connection>(() => {
  if (polling.value === "lost" || socket.value === "lost") return "lost";
  return polling.value === "online" && socket.value === "online" ? "online" : "connecting";
});
export const online = computed(() => connection.value === "online");

export const STATUS_PERIOD_MS = 100;
const SERVICE_PERIOD_MS = 1000;

export const axis = (name: string) => status.value?.axes.find((a) => a.name === name) ?? null;

/** A machine's route; throws while no machine is chosen (never `/api/machines//…`). */
export function machineUrl(path = ""): string {
  if (!machineId.value) throw new Error("no machine chosen yet");
  return `/api/machines/${encodeURIComponent(machineId.value)}${path}`;
}

/** Motion commands are refused in an emergency stop until reset: their buttons say so. */
export const motionLocked = computed(() => !online.value || !!status.value?.emergency_stop);

async function pollStatus(): Promise<void> {
  if (!machineId.value) return;
  try {
    status.value = await http.get<MachineStatus>(machineUrl("/status"));
    polling.value = "online";
  } catch (e) {
    if (e instanceof ApiError && e.status === 0) polling.value = "lost";
  }
}

async function pollService(): Promise<void> {
  try {
    service.value = await http.get<ServiceStatus>("/api/service/status");
  } catch {
    /* the status poll reports the connection */
  }
}

/** Load the machine list and start polling (the first machine unless `#machine` says). */
export async function startSession(): Promise<void> {
  for (;;) {
    try {
      machines.value = await http.get<MachineSummary[]>("/api/machines");
      break;
    } catch {
      polling.value = "lost";
      await new Promise((r) => setTimeout(r, 1000));
    }
  }
  const wanted = location.hash.slice(1);
  machineId.value = machines.value.find((m) => m.id === wanted)?.id ?? machines.value[0]?.id ?? "";
  let busy = false;
  setInterval(async () => {
    if (busy) return; // never stack requests behind a slow answer
    busy = true;
    await pollStatus();
    busy = false;
  }, STATUS_PERIOD_MS);
  setInterval(pollService, SERVICE_PERIOD_MS);
  void pollService();
}

export function selectMachine(id: string): void {
  machineId.value = id;
  status.value = null;
  location.hash = id;
}

/** Send one command; resolves to the acknowledgement, rejects with the refusal (ApiError). */
export async function send(cmd: Command): Promise<CommandResult> {
  const result = await http.post<CommandResult>(machineUrl("/commands"), cmd);
  void pollStatus(); // show the effect without waiting for the next poll
  return result;
}
