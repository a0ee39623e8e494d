// The trainer's roster: students as people across classes, each with their results.
import { signal } from "@preact/signals";
import { http } from "../api/http";
import type { RosterStudent, StudentRecord } from "../api/types";

/** Everybody on the roster, by name (loaded when the console or the class form asks). */
export const roster = signal<RosterStudent[]>([]);

export async function loadRoster(): Promise<void> {
  roster.value = await http.get<RosterStudent[]>("/api/roster");
}

export const studentRecord = (pid: number) => http.get<StudentRecord>(`/api/roster/${pid}`);

export async function forgetStudent(pid: number): Promise<void> {
  await http.del(`/api/roster/${pid}`);
  await loadRoster();
}
