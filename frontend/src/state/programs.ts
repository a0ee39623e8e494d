// Stored NC programs (service-wide) and a program's preview on the shown machine.
import { http } from "../api/http";
import type { Program, ProgramInfo, ProgramPreview } from "../api/types";
import { machineUrl } from "./session";

const url = (name: string) => `/api/programs/${encodeURIComponent(name)}`;

export const listPrograms = () => http.get<ProgramInfo[]>("/api/programs");
export const readProgram = (name: string) => http.get<Program>(url(name));
export const writeProgram = (name: string, text: string) => http.put<ProgramInfo>(url(name), { text });
export const deleteProgram = (name: string) => http.del<void>(url(name));
/** The first error and the commanded tool path, interpreted from the machine's position. */
export const previewProgram = (text: string) => http.post<ProgramPreview>(machineUrl("/program-preview"), { text });

/** As api/commands.py ProgramName: letters, digits, _ . - (1-64, not starting with . or -). */
export const PROGRAM_NAME = /^[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}$/;

/** A program name from a file name: other characters become _, at most 64. */
export function nameFromFile(file: string): string {
  const name = file.replace(/[^A-Za-z0-9_.-]/g, "_").replace(/^[.-]+/, "").slice(0, 64);
  return name || "program";
}
