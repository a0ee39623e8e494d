// MDI: one block, a history (↑/↓), and a refused block shown with a caret under its column.
import { useState } from "preact/hooks";
import { commandBlocked } from "../state/control";
import { motionLocked, online, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine, useCommand } from "../ui/useCommand";

/** The MDI input with Execute, a refused block's caret and the refusal: the MDI panel's and
 * the scope's command strip's. `line` is the parent's (its history fills it). */
export function MdiLine(props: { line: string; setLine: (l: string) => void; history: string[]; onSent: (block: string) => void }) {
  const { line, setLine, history } = props;
  const [pos, setPos] = useState(-1); // index into history while browsing, -1: editing
  const [sent, setSent] = useState("");
  const cmd = useCommand();

  async function submit() {
    const block = line.trim();
    if (!block) return;
    setSent(block);
    props.onSent(block);
    setPos(-1);
    const ok = await cmd.run({ type: "mdi", block });
    if (ok) setLine("");
  }

  function browse(step: number) {
    const next = Math.max(-1, Math.min(history.length - 1, pos + step));
    setPos(next);
    setLine(next < 0 ? "" : history[next]);
  }

  const column = cmd.refusal?.column ?? null;
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  return (
    <>
      <form
        class="row mdi-form"
        onSubmit={(e) => {
          e.preventDefault();
          void submit();
        }}
      >
        <input
          class="mdi-line"
          data-testid="mdi-input"
          aria-label="NC block"
          placeholder="e.g. M3 S1000   G01 X60 F600   M19 S.POS=90"
          value={line}
          spellcheck={false}
          autocomplete="off"
          disabled={!online.value || !!blocked}
          title={blocked}
          onInput={(e) => setLine((e.target as HTMLInputElement).value)}
          onKeyDown={(e) => {
            if (e.key === "ArrowUp") (e.preventDefault(), browse(1));
            if (e.key === "ArrowDown") (e.preventDefault(), browse(-1));
          }}
        />
        <button type="submit" data-testid="mdi-send" disabled={motionLocked.value || !line.trim() || !!blocked}
          title={blocked || (status.value?.emergency_stop ? "emergency stop: reset first" : "")}>
          Execute
        </button>
      </form>
      {column !== null ? (
        <pre class="mdi-error" data-testid="mdi-error" data-column={column} aria-label={`error at column ${column}`}>
          {sent}
          {"\n"}
          {" ".repeat(column - 1)}^ column {column}
        </pre>
      ) : null}
      <RefusalLine refusal={cmd.refusal} id="mdi-refusal" />
    </>
  );
}

/** A block history, newest first, without repeats. */
export const withBlock = (h: string[], block: string) => [block, ...h.filter((b) => b !== block)].slice(0, 50);

export function MdiPanel() {
  const [line, setLine] = useState("");
  const [history, setHistory] = useState<string[]>([]);
  return (
    <Panel title="MDI" id="mdi">
      <MdiLine line={line} setLine={setLine} history={history} onSent={(b) => setHistory((h) => withBlock(h, b))} />
      <MdiState />
      {history.length ? (
        <ol class="history" aria-label="MDI history">
          {history.slice(0, 8).map((b) => (
            <li key={b}>
              <button type="button" class="link" onClick={() => setLine(b)} title="copy to the input (does not execute)">
                {b}
              </button>
            </li>
          ))}
        </ol>
      ) : null}
    </Panel>
  );
}

/** What MDI runs and which modal words the next block starts from (they carry over). */
export function MdiState() {
  const s = status.value;
  const ch = s?.channel;
  if (!s || !ch) return null;
  const md = ch.modal;
  const words = [md.motion, md.plane, md.distance, md.feed_mm_min != null ? `F${md.feed_mm_min}` : "no F"]
    .concat(md.manual_mode === "G201" ? ["G201"] : [])
    .join(" ");
  // queued_blocks counts the running block too: "1 block queued" beside the only one read wrong
  const waiting = Math.max(0, s.queued_blocks - 1);
  const running = ch.mdi ? `running${waiting ? `, ${waiting} more block${waiting === 1 ? "" : "s"} waiting` : ""}` : "idle";
  const held = ch.mdi && ch.state === "held" ? " (feedhold)" : "";
  return (
    <p class="mdi-state muted" data-testid="mdi-state" data-mdi={ch.mdi ? "1" : "0"}
      title="MDI blocks run through the channel; G00-G03, G17-G19, G90/G91 and F carry over to the next block (reset: G00 G17 G90, no F)">
      MDI {running}{held} · in force: <span data-testid="mdi-modal">{words}</span>
      {ch.mdi && ch.waiting_for ? ` · waiting for ${ch.waiting_for}` : ""}
    </p>
  );
}
