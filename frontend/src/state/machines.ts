// Managing machines from the HMI (one place, the Machines dialog): the list, create (the demo
// or uploaded lists), restart, delete, and the pacing of the simulation of the machine on screen.
import { signal } from "@preact/signals";
import { http } from "../api/http";
import type { MachineSummary, ParameterValue, SimulationStatus } from "../api/types";
import { loadList } from "./params";
import { machineId, machines, machineUrl, selectMachine, status } from "./session";

/** Whether the Machines dialog is open. */
export const machinesOpen = signal(false);

/** Read the machine list again (after a create or delete, or when the dialog opens). */
export async function refreshMachines(): Promise<void> {
  machines.value = await http.get<MachineSummary[]>("/api/machines");
}

/** A new machine: the demo, or native lists (axis lists by logical axis number). */
export interface NewMachine {
  id: string;
  name: string;
  demo: boolean;
  channel_list: string;
  axis_lists: Record<number, string>;
  tool_list: string;
}

export async function createMachine(req: NewMachine): Promise<MachineSummary> {
  const m = await http.post<MachineSummary>("/api/machines", req);
  await refreshMachines();
  return m;
}

/** Power the machine on screen off and on: cycle 0, every stored value in force. */
export async function restartMachine(): Promise<MachineSummary> {
  return http.post<MachineSummary>(machineUrl("/restart"), {});
}

/** Delete a machine; the one on screen gives way to the first one left. */
export async function deleteMachine(id: string): Promise<void> {
  await http.del<void>(`/api/machines/${encodeURIComponent(id)}`);
  await refreshMachines();
  if (machineId.value === id) selectMachine(machines.value[0]?.id ?? "");
}

/** Run in real time, pause, or run as fast as it can. */
export async function pace(mode: "run" | "pause" | "fast"): Promise<SimulationStatus> {
  return http.post<SimulationStatus>(machineUrl("/simulation"), { mode });
}

/** Pause and advance `cycles` cycles. */
export async function stepCycles(cycles: number): Promise<SimulationStatus> {
  return http.post<SimulationStatus>(machineUrl("/simulation/step"), { cycles });
}

/** A value written and waiting for the restart to take effect. */
export interface PendingRestart {
  list: string;
  value: ParameterValue;
}

/** Every value of the machine's lists that waits for a restart (channel, axes, tools). */
export async function pendingRestart(): Promise<PendingRestart[]> {
  const lists: [string, Promise<ParameterValue[]>][] = [
    ["Channel", loadList("channel", null)],
    ...(status.value?.axes ?? []).map((a): [string, Promise<ParameterValue[]>] => [`Axis ${a.name}`, loadList("axis", a.name)]),
    ["Tools", loadList("tool", null)],
  ];
  const out: PendingRestart[] = [];
  for (const [list, rows] of lists)
    for (const value of await rows) if (value.pending != null && value.effect === "restart") out.push({ list, value });
  return out;
}
