// Parts the calculators share: a number checked as typed, a labelled field with its unit
// and error, and Apply on trial (Keep / Revert in the trial bar).
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { AssistChange, Refusal } from "../api/types";
import { applyProposal } from "../state/assist";
import { configureBlocked } from "../state/control";
import { trial } from "../state/params";
import { online } from "../state/session";
import { RefusalLine } from "../ui/useCommand";

export const refusalOf = (e: unknown): Refusal =>
  e instanceof ApiError ? e.refusal : { message: e instanceof Error ? e.message : String(e), problems: [] };

/** A number typed into a field: its value within [lo, hi] ((lo, hi] when `loOpen`), or why not. */
export function checkNumber(text: string, what: string, lo: number, hi: number, unit: string, loOpen = false, integer = false): number | string {
  const t = text.trim();
  const v = Number(t);
  if (t === "" || !Number.isFinite(v)) return `${what}: a number is needed`;
  if (integer && !Number.isInteger(v)) return `${what}: a whole number is needed`;
  if ((loOpen ? v <= lo : v < lo) || v > hi) return `${what}: ${loOpen ? `> ${lo}` : `≥ ${lo}`} and ≤ ${hi}${unit ? ` ${unit}` : ""}`;
  return v;
}

/** One labelled input with its unit and the error beside it as typed. */
export function Field(props: {
  label: string;
  unit: string;
  value: string;
  check: number | string;
  testid: string;
  onInput: (v: string) => void;
  size?: number;
}) {
  const bad = typeof props.check === "string";
  return (
    <label class="assist-field">
      <span>{props.label}</span>
      <span class="row">
        <input data-testid={props.testid} size={props.size ?? 10} value={props.value} aria-invalid={bad}
          onInput={(e) => props.onInput((e.target as HTMLInputElement).value)} />
        <span>{props.unit}</span>
      </span>
      {bad ? (
        <span class="inline-error" data-testid={`${props.testid}-error`} role="alert">
          {props.check as string}
        </span>
      ) : null}
    </label>
  );
}

/** Apply on trial (one list), with the note that Keep / Revert follow in the trial bar. */
export function ApplyBar(props: { assistant: string; changes: AssistChange[]; testid: string; onApplied?: () => void }) {
  const [applied, setApplied] = useState(false);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const blocked = configureBlocked.value;
  const onTrial = !!trial.value;
  useEffect(() => setApplied(false), [props.changes]);
  async function apply() {
    setRefusal(null);
    try {
      await applyProposal(props.assistant, props.changes);
      setApplied(true);
      props.onApplied?.();
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }
  return (
    <>
      <div class="row apply-bar">
        <button type="button" data-testid={`${props.testid}-apply`}
          disabled={!online.value || !props.changes.length || onTrial || !!blocked}
          title={blocked || (onTrial ? "Keep or Revert the values on trial first" : "")} onClick={() => void apply()}>
          Apply on trial
        </button>
        {applied ? (
          <span class="hint" data-testid={`${props.testid}-applied`}>
            Applied: Keep or Revert in the trial bar above.
          </span>
        ) : blocked ? (
          <span class="hint">{blocked}</span>
        ) : onTrial ? (
          <span class="hint">Values are on trial: Keep or Revert them first.</span>
        ) : null}
      </div>
      <RefusalLine refusal={refusal} id={`${props.testid}-apply-refusal`} />
    </>
  );
}
