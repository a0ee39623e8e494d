// Topic groups of the parameter editor, from the list names' first segment.
const TOPICS: Record<string, string> = {
  kenngr: "Characteristics (kenngr)",
  handbetrieb: "Manual mode / jog (handbetrieb)",
  antr: "Drive (antr)",
  lr_hw: "Position control hardware (lr_hw)",
  lr_param: "Position control (lr_param)",
  sim: "Simulated machine: plant and mechanics (sim)",
  drive: "Drive controller, SINAMICS numbering (drive)",
  kopf: "Header (kopf)",
  spindel: "Spindles (spindel)",
  achse: "Path axes (achse)",
  vector: "Path dynamics (vector)",
  prog_start: "Program start (prog_start)",
  plc: "PLC",
  wz: "Tools (wz)",
};

/** The group a concrete list name belongs to, e.g. "Gear record getriebe[2] (M42 · gear 3)". */
export function groupOf(name: string, gear: number | null | undefined, spindle: boolean): string {
  if (gear) return `Gear record getriebe[${gear - 1}] (${spindle ? `M${39 + gear} · ` : ""}gear ${gear})`;
  const head = name.split(/[.[]/)[0];
  return TOPICS[head] ?? "General";
}
