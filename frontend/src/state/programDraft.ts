// The Program editor's draft, one per machine: it outlives the panel (switching workspaces
// unmounts it) and a reload of the tab (sessionStorage: this tab only, gone with it).

/** What this tab loaded into the machine's channel last (the name and the exact text). */
export interface Loaded {
  name: string;
  text: string;
}

export interface Draft {
  name: string;
  text: string;
  saved: string | null; // the text as stored under `name`, null when never saved or opened
  loaded: Loaded | null;
}

/** The "New" program: a turned diameter with a quarter-circle shoulder (G18: Z across, X up).
 * The arc from X40 Z-20 to X50 Z-30 about the centre X50 Z-20 (I10 K0) has radius 10 at
 * both ends; its chord is 14.1 mm, so the radius is more than half the chord, as it must be. */
export const NEW_PROGRAM =
  "; a new program (G18: Z across, X up)\nG18 G90\nG00 X40 Z5\nG01 Z-20 F300\nG02 X50 Z-30 I10 K0\nG01 Z-40\nG00 X80\nZ5\nM30\n";
export const NEW_NAME = "new_program.nc";

export const newDraft = (): Draft => ({ name: NEW_NAME, text: NEW_PROGRAM, saved: null, loaded: null });

const key = (machine: string) => `inbetrieb.program-draft.${machine}`;

/** The machine's draft (a new program when there is none). */
export function readDraft(machine: string): Draft {
  try {
    const d = JSON.parse(sessionStorage.getItem(key(machine)) ?? "null") as Draft | null;
    if (d && typeof d.name === "string" && typeof d.text === "string") return { ...newDraft(), ...d };
  } catch {
    // a draft that does not parse is dropped: the editor starts anew
  }
  return newDraft();
}

export function writeDraft(machine: string, d: Draft): void {
  if (!machine) return;
  try {
    sessionStorage.setItem(key(machine), JSON.stringify(d));
  } catch {
    // storage full or blocked: the draft lives as long as the panel
  }
}
