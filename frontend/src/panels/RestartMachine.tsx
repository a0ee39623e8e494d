// Restarting the machine on screen, asked first: the one control for it, in the Machines
// dialog and in the trial bar beside values that wait for a restart. A restart is a command:
// it needs control (the button says why not). What it did is said once done.
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { commandBlocked } from "../state/control";
import { restartMachine } from "../state/machines";
import { online } from "../state/session";
import { RefusalLine } from "../ui/useCommand";

/** `onDone` takes the "restarted" line where it must outlive the button (the trial bar drops
 * the button once nothing waits for a restart any more); else the button shows it. */
export function RestartMachine({ label = "⟳ Restart…", refusalId, onDone }: { label?: string; refusalId: string; onDone?: (text: string) => void }) {
  const [confirm, setConfirm] = useState(false);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [done, setDone] = useState("");
  const why = commandBlocked.value;
  const dis = !online.value || !!why;
  const restart = async () => {
    try {
      const m = await restartMachine();
      setRefusal(null);
      const text = `Restarted ${m.id} at ${new Date().toLocaleTimeString()}: every stored value is in force.`;
      if (onDone) onDone(text);
      else setDone(text);
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
    }
    setConfirm(false);
  };
  return (
    <>
      {confirm ? (
        <>
          <span>Power off and on: the machine starts again at cycle 0 with every stored value in force.</span>
          <button type="button" class="danger" data-testid="restart-confirm" disabled={dis} title={why} onClick={() => void restart()}>
            Restart now
          </button>
          <button type="button" class="secondary" onClick={() => setConfirm(false)}>Cancel</button>
        </>
      ) : (
        <button type="button" class="secondary" data-testid="machine-restart" disabled={dis} title={why}
          onClick={() => (setDone(""), setConfirm(true))}>
          {label}
        </button>
      )}
      {done && !confirm ? <span class="hint" role="status" data-testid="restart-done">{done}</span> : null}
      <RefusalLine refusal={refusal} id={refusalId} />
    </>
  );
}
