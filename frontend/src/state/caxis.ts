// The rotary-axis name of the main spindle (P-CHAN-00010 default_ax_name_of_spindle): the
// status shows it only while the spindle is the rotary axis, the jog and mode keys need it before.
import { signal } from "@preact/signals";
import { loadList } from "./params";

/** The rotary-axis name ("C"), null without rotary-axis capability or before it is loaded. */
export const rotaryAxisName = signal<string | null>(null);

/** Read P-CHAN-00010 of the machine anew (after a machine switch or a parameter write). */
export async function loadRotaryAxisName(): Promise<void> {
  try {
    const channel = await loadList("channel", null);
    const v = channel.find((p) => p.id === "P-CHAN-00010")?.value;
    rotaryAxisName.value = typeof v === "string" && v.trim() ? v.trim().toUpperCase() : null;
  } catch {
    rotaryAxisName.value = null;
  }
}
