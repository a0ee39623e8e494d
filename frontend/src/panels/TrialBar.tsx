// Values applied on trial stay on screen in every workspace until Keep or Revert, so the
// engineer can switch to Operate, test them, and still revert.
import { configureBlocked } from "../state/control";
import { keepTrial, revertTrial, shownTrial, trialMessage } from "../state/params";
import { online } from "../state/session";

const SHOWN = 6; // changes listed; a rollback may bring many

export function TrialBar() {
  const t = shownTrial.value;
  const msg = trialMessage.value;
  if (!t && !msg) return null;
  return (
    <div class="trial-bar" data-testid="trial-bar">
      {t ? (
        <span class="trial" data-testid="param-trial" role="status">
          Parameters on trial ({t.label ?? t.target ?? t.scope}):{" "}
          {t.applied
            .slice(0, SHOWN)
            .map((c) => `${t.label && c.target ? `${c.target}: ` : ""}${c.name} ${c.old ?? "default"} → ${c.new}${c.pending ? ` (at ${c.effect})` : ""}`)
            .join(", ")}
          {t.applied.length > SHOWN ? ` … and ${t.applied.length - SHOWN} more` : ""}
          <button type="button" data-testid="param-keep" onClick={keepTrial}>
            Keep
          </button>
          <button type="button" data-testid="param-revert" class="secondary" disabled={!online.value || !!configureBlocked.value}
            title={configureBlocked.value}
            onClick={() => void revertTrial()}>
            Revert
          </button>
        </span>
      ) : null}
      {msg ? <span class="hint" data-testid="trial-message">{msg}</span> : null}
    </div>
  );
}
