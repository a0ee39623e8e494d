// Send commands from a panel: busy while in flight, the refusal kept to show under the buttons.
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Command, CommandResult, Refusal } from "../api/types";
import { send } from "../state/session";

export function useCommand() {
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  /** Send `cmd` to the machine (or make another request that answers like one). */
  async function run(cmd: Command | (() => Promise<CommandResult>)): Promise<CommandResult | null> {
    setBusy(true);
    try {
      const r = await (typeof cmd === "function" ? cmd() : send(cmd));
      setRefusal(null);
      return r;
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
      return null;
    } finally {
      setBusy(false);
    }
  }
  return { run, refusal, busy, clear: () => setRefusal(null) };
}

export function RefusalLine(props: { refusal: Refusal | null; id?: string }) {
  const r = props.refusal;
  if (!r) return null;
  return (
    <p class="refusal" role="alert" data-testid={props.id}>
      {r.code ? <b>{r.code}</b> : null} {r.message}
    </p>
  );
}
