// A commissioning assistant running live on the machine, as everyone watching sees it: which,
// on which axis, by whom, the phase and the simulated time against the plan, and Cancel
// (any operator, like the E-stop).
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import { cancelLive, liveRun } from "../state/assist";
import { may } from "../state/control";

export function LiveProgress({ compact = false }: { compact?: boolean }) {
  const run = liveRun.value;
  const [why, setWhy] = useState("");
  if (!run) return null;
  const pct = run.planned_s > 0 ? Math.min(100, (100 * run.elapsed_s) / run.planned_s) : 0;
  async function cancel() {
    try {
      await cancelLive();
      setWhy("");
    } catch (e) {
      setWhy(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }
  return (
    <div class={compact ? "assist-live compact" : "assist-live"} role="status" data-testid={compact ? "banner-assist" : "assist-live"}>
      <span>
        ▶ <b>{run.name}</b> on {run.axis} by {run.by}: {run.phase}
      </span>
      <progress max={100} value={pct} aria-label="the run's progress" />
      <span class="num">
        {run.elapsed_s.toFixed(1)} / {run.planned_s.toFixed(1)} s
      </span>
      {may("stop") ? (
        <button type="button" class="danger" data-testid={compact ? "banner-assist-cancel" : "assist-cancel"} onClick={() => void cancel()}>
          Cancel run
        </button>
      ) : null}
      {why ? <span class="inline-error">{why}</span> : null}
    </div>
  );
}
