// Values applied on trial stay on screen in every workspace until Keep or Revert, so the
// engineer can switch to Operate, test them, and still revert. A value that waits for a
// restart says so until the machine has restarted (by anyone), and the bar offers the restart.
import { configureBlocked, may } from "../state/control";
import { changeKey, keepTrial, revertTrial, revertWaitsForRestart, shownTrial, type Trial, trialMessage, trialNow } from "../state/params";
import { online } from "../state/session";
import { engQty } from "../ui/format";
import { RestartMachine } from "./RestartMachine";

const SHOWN = 6; // changes listed; a rollback may bring many

type Applied = Trial["applied"][number];

/** The change still waits for its reset or restart (as the list stands now; as applied while
 * the list is not loaded yet). */
function waits(c: Applied): boolean {
  if (!c.pending) return false;
  const p = trialNow.value.get(changeKey(c));
  return p ? p.pending != null && p.version === c.version : true;
}

/** " (20 → 30 1/s)": the change in the HMI's unit beside the list's raw values, where they
 * differ (a kv in 0.01/s, a position in 0.1 µm). */
function inHmiUnit(c: Applied, all: Applied[]): string {
  const mg = /^(.*multi_gain_)([zn])$/.exec(c.name);
  if (mg) return mg[2] === "z" ? multiGainRatio(c, mg[1], all) : "";
  const p = trialNow.value.get(changeKey(c));
  const f = p?.eng_factor;
  if (!p || f == null || f === 1) return "";
  const eng = (v: unknown) => (typeof v === "number" ? engQty(v * f, p.eng_unit) : null);
  const after = eng(c.new);
  return after === null ? "" : ` (${eng(c.old ?? p.default) ?? "—"} → ${after})`;
}

/** multi_gain_z and _n read as their ratio, once beside _z (22857/1 → 22853561/1000 read as a
 * 2285-fold change): " (multi_gain 2.2857 → 2.2854)". */
function multiGainRatio(z: Applied, base: string, all: Applied[]): string {
  const n = all.find((c) => c.name === `${base}n` && c.target === z.target);
  const nNow = trialNow.value.get(changeKey({ ...z, name: `${base}n` }));
  const nOld = n ? n.old : nNow?.value;
  const nNew = n ? n.new : nNow?.value;
  const ratio = (a: unknown, b: unknown) => (typeof a === "number" && typeof b === "number" && b !== 0 ? String(+(a / b).toPrecision(5)) : null);
  const before = ratio(z.old, nOld);
  const after = ratio(z.new, nNew);
  return after === null ? "" : ` (multi_gain ${before ?? "—"} → ${after})`;
}

export function TrialBar() {
  const t = shownTrial.value;
  const msg = trialMessage.value;
  if (!t && !msg) return null;
  const restartWaits = t ? t.applied.some((c) => c.effect === "restart" && waits(c)) : revertWaitsForRestart.value;
  return (
    <div class="trial-bar" data-testid="trial-bar">
      {t ? (
        <span class="trial" data-testid="param-trial" role="status">
          Parameters on trial ({t.label ?? t.target ?? t.scope}):{" "}
          {t.applied
            .slice(0, SHOWN)
            .map(
              (c) =>
                `${t.label && c.target ? `${c.target}: ` : ""}${c.name} ${c.old ?? "default"} → ${c.new}` +
                inHmiUnit(c, t.applied) +
                (waits(c) ? ` (at ${c.effect})` : c.pending ? ` (in force since the ${c.effect})` : ""),
            )
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
      {msg ? (
        <span class={msg.includes("refused") ? "done-note refused" : "done-note"} data-testid="trial-message" role="status">
          {msg}
        </span>
      ) : null}
      {restartWaits && may("command") ? (
        <RestartMachine label="⟳ Restart now…" refusalId="trial-restart-refusal" onDone={(text) => (trialMessage.value = text)} />
      ) : null}
    </div>
  );
}
