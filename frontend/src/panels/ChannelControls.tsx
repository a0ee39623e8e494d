// The NC channel: load the program, cycle start, feedhold, single block, stop; its state,
// the block it is in and what it waits for, from the pushed status.
import type { ChannelStatus, Command } from "../api/types";
import { commandBlocked } from "../state/control";
import { motionLocked, online, status } from "../state/session";
import { useCommand } from "../ui/useCommand";

export function ChannelControls(props: {
  load: Command | null; // the program_load for the program in the editor
  canLoad: string; // why it cannot be loaded ("" when it can)
}) {
  const cmd = useCommand();
  const s = status.value;
  const ch: ChannelStatus | null = s?.channel ?? null;
  const blocked = commandBlocked.value;
  const off = !online.value || !!blocked;
  const feedhold = !!s?.channel_units.feedhold;
  const r = cmd.refusal;
  return (
    <div class="channel" data-testid="channel">
      <div class="row">
        <button type="button" data-testid="program-load" disabled={off || !!props.canLoad} title={blocked || props.canLoad || "load this program into the channel"}
          onClick={() => props.load && void cmd.run(props.load)}>
          Load
        </button>
        <button type="button" data-testid="cycle-start" disabled={off || motionLocked.value} title={blocked || "run the loaded program, or continue it"}
          onClick={() => void cmd.run({ type: "cycle_start" })}>
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
        <dt>State</dt>
        <dd data-testid="channel-state" class={`ch-${ch?.state ?? "idle"}`}>{ch?.state ?? "—"}</dd>
        <dt>Program</dt>
        <dd data-testid="channel-program">{ch?.program ?? "—"}</dd>
        <dt>Block line</dt>
        <dd data-testid="channel-block-line">{ch?.block_line ?? "—"}</dd>
        <dt>Blocks done</dt>
        <dd>{ch?.blocks_done ?? 0}</dd>
        <dt>Waiting for</dt>
        <dd data-testid="channel-waiting">{ch?.waiting_for ?? "—"}</dd>
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
