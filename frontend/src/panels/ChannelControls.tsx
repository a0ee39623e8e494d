// The NC channel: load the program, cycle start, feedhold, single block, stop; its state in
// the operator's words, the block it is in, the path feed, the modal state, the spindle (by
// its configured name) and what the path waits for, from the pushed status.
import type { ChannelStatus, CommandResult, MachineStatus } from "../api/types";
import { commandBlocked } from "../state/control";
import { motionLocked, online, status } from "../state/session";
import { fmt, qty } from "../ui/format";
import { useCommand } from "../ui/useCommand";

/** The channel's state as an operator reads it (api/status.py ChannelStateName). */
export function channelWords(ch: ChannelStatus | null | undefined): string {
  switch (ch?.state) {
    case undefined:
      return "—";
    case "idle":
      return "No program (MDI)";
    case "ready":
      // a program that ran (to M30 or Stop) keeps its last block line; a fresh load has none
      return ch.block_line !== null ? "Program ended — ready" : "Ready";
    case "running":
      return "Running";
    case "held":
      return "Feedhold";
    case "block_end":
      return "Block end (single block)";
    case "error":
      return "Stopped by an error";
  }
}

/** The main spindle's configured name ("S1"): programs address it as S. */
export const mainSpindle = (s: MachineStatus | null | undefined) => s?.axes.find((a) => a.kind === "spindle") ?? null;

/** The channel's words with the spindle address S replaced by the spindle's name. */

export function ChannelControls(props: {
  load: (() => Promise<CommandResult>) | null; // loads the program in the editor
  canLoad: string; // why it cannot be loaded ("" when it can)
}) {
  const cmd = useCommand();
  const s = status.value;
  const ch: ChannelStatus | null = s?.channel ?? null;
  const sp = mainSpindle(s);
  const blocked = commandBlocked.value;
  const off = !online.value || !!blocked;
  const feedhold = !!s?.channel_units.feedhold;
  const noProgram = !ch?.program || ch.state === "idle" ? "load a program first" : "";
  const r = cmd.refusal;
  const m = ch?.modal;
  return (
    <div class="channel" data-testid="channel">
      <div class="row channel-buttons">
        <button type="button" data-testid="program-load" disabled={off || !!props.canLoad} title={blocked || props.canLoad || "load this program into the channel"}
          onClick={() => props.load && void cmd.run(props.load)}>
          Load
        </button>
        <button type="button" data-testid="cycle-start" disabled={off || motionLocked.value || !!noProgram}
          title={blocked || noProgram || "run the loaded program, or continue it"} onClick={() => void cmd.run({ type: "cycle_start" })}>
          ▶ Cycle start
        </button>
        <button type="button" class="secondary" data-testid="feedhold" aria-pressed={feedhold} disabled={off}
          title={blocked || "the path brakes on its contour and waits"} onClick={() => void cmd.run({ type: "feedhold", on: !feedhold })}>
          ❚❚ Feedhold
        </button>
        <button type="button" class="secondary" data-testid="single-block" aria-pressed={!!ch?.single_block} disabled={off}
          title={blocked || "stop after every block until cycle start"} onClick={() => void cmd.run({ type: "single_block", on: !ch?.single_block })}>
          Single block
        </button>
        <button type="button" class="stop" data-testid="program-stop" disabled={off} title={blocked || "stop the program and rewind it"}
          onClick={() => void cmd.run({ type: "program_stop" })}>
          ■ Stop
        </button>
      </div>
      <dl class="channel-state">
        <div>
          <dt>State</dt>
          <dd data-testid="channel-state" data-state={ch?.state ?? ""} class={`ch-${ch?.state ?? "idle"}`}>{channelWords(ch)}</dd>
        </div>
        <div>
          <dt>Program</dt>
          <dd data-testid="channel-program">{ch?.program ?? "—"}</dd>
        </div>
        <div>
          <dt>Block line</dt>
          <dd data-testid="channel-block-line">{ch?.block_line ?? "—"}</dd>
        </div>
        <div>
          <dt>Blocks done</dt>
          <dd>{ch?.blocks_done ?? 0}</dd>
        </div>
        <div>
          <dt>Path feed</dt>
          <dd data-testid="channel-feed" title="commanded path velocity now (F in force)">
            {qty(ch?.path_feed_mm_min, 0, "mm/min")}
            {m?.feed_mm_min ? <span class="hint"> (F{fmt(m.feed_mm_min, 0)})</span> : null}
          </dd>
        </div>
        <div>
          <dt>Modal</dt>
          <dd data-testid="channel-modal">{m ? `${m.motion} ${m.plane} ${m.distance}` : "—"}</dd>
        </div>
        {sp ? (
          <div>
            <dt>{sp.name}</dt>
            <dd data-testid="channel-spindle" title={`${sp.name}: actual speed (programmed S ${fmt(sp.speed_prog_rpm, 0)} rpm)`}>
              {qty(sp.vel_act, 0, "rpm")}
            </dd>
          </div>
        ) : null}
        <div class="wide">
          <dt>Waiting for</dt>
          <dd data-testid="channel-waiting">{ch?.waiting_for ?? "—"}</dd>
        </div>
      </dl>
      {ch?.error ? (
        <p class="refusal" data-testid="channel-error">
          {ch.error.code} {ch.error.message}
          {ch.error.line ? ` (line ${ch.error.line}${ch.error.column ? `, column ${ch.error.column}` : ""})` : ""}
        </p>
      ) : null}
      {r ? (
        <p class="refusal" role="alert" data-testid="program-refusal">
          {r.code ? <b>{r.code}</b> : null} {r.message}
          {r.line ? ` (line ${r.line}${r.column ? `, column ${r.column}` : ""})` : ""}
        </p>
      ) : null}
    </div>
  );
}
