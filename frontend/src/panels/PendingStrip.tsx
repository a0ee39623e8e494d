// Under the top bar, on every workspace: each handshake the NC waits for from the PLC (a gear
// change's M40-M45, an M function, a changeover's mode request), the time left before it gives
// up with job error 90004, and — while the PLC is acknowledged by hand — the key to answer it
// for those who may command. The HLI / PLC workspace shows the same with the signals.
import { commandBlocked } from "../state/control";
import { answerOf, pendingHandshakes, secondsLeft, waitedFor } from "../state/handshakes";
import { online, status } from "../state/session";
import { fmt } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";

export function PendingStrip() {
  const cmd = useCommand();
  const pending = pendingHandshakes.value;
  const plc = status.value?.plc;
  if (!pending.length || !plc) return null;
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  const timeoutS = (p: (typeof pending)[number]) =>
    p.timeout_cycle != null && status.value ? (p.timeout_cycle - p.out_cycle) * status.value.simulation.cycle_s : null;
  return (
    <div class="pending-strip" role="status" aria-label="the NC waits for the PLC" data-testid="pending-strip">
      {pending.map((p) => {
        const left = secondsLeft(p);
        const total = timeoutS(p);
        const answer = answerOf(p);
        const tid = p.signal ?? `m${p.m}`;
        return (
          <div class="pending-item" key={`${tid}-${p.out_cycle}`} data-testid={`pending-strip-${tid}`}>
            <span>
              The NC waits: <b data-testid="pending-what">{waitedFor(p)}</b>
            </span>
            {left !== null ? (
              <span class="pending-left" title="then job error 90004 (P-CHAN plc.m_ack_timeout)">
                <span data-testid="pending-left">{fmt(left, 1)}</span>&nbsp;s left
                {total ? <meter min={0} max={total} value={left} low={total * 0.3} optimum={total} aria-hidden="true" /> : null}
              </span>
            ) : null}
            {plc.mode === "manual" ? (
              <button type="button" data-testid={`pending-ack-${tid}`} disabled={!online.value || !!blocked} title={blocked}
                onClick={() => void cmd.run(answer.cmd)}>
                {answer.label}
              </button>
            ) : (
              <span class="hint">
                {plc.mode === "fault" ? "the PLC does not answer (fault mode)" : "the PLC has not answered yet"}
              </span>
            )}
          </div>
        );
      })}
      <RefusalLine refusal={cmd.refusal} id="pending-refusal" />
    </div>
  );
}
