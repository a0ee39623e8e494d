// The open class live: a bar of actions on the selected seats (or the whole class) and one
// tile per seat, fed by the grid websocket.
import { useState } from "preact/hooks";
import type { ClassInfo } from "../api/types";
import { broadcast, endClass, freeze, gridLink, seats, selected } from "../state/classes";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { SeatTile } from "./SeatTile";
import { act, actionRefusal, faultFor } from "./uiState";

function ClassBar(props: { c: ClassInfo }) {
  const { c } = props;
  const [text, setText] = useState("");
  const [sent, setSent] = useState(""); // "sent to N seats", until the next message is typed
  const [ending, setEnding] = useState(false); // asking whether to end the class
  const picked = [...selected.value].sort((a, b) => a - b);
  const target = picked.length ? `seat${picked.length > 1 ? "s" : ""} ${picked.join(", ")}` : "the whole class";
  return (
    <div class="class-bar" aria-label="actions on seats">
      <span class="hint" data-testid="grid-target">
        To: <b>{target}</b>
      </span>
      <button type="button" class="link" onClick={() => (selected.value = new Set(c.seats.map((s) => s.n)))}>all</button>
      <button type="button" class="link" onClick={() => (selected.value = new Set())} disabled={!picked.length}>none</button>
      <button type="button" class="secondary" data-testid="grid-freeze" onClick={() => void act(() => freeze(c.id, picked, true))}>
        Freeze
      </button>
      <button type="button" class="secondary" data-testid="grid-resume" onClick={() => void act(() => freeze(c.id, picked, false))}>
        Resume
      </button>
      <button type="button" class="secondary" data-testid="grid-fault" onClick={() => (faultFor.value = picked)}>
        Inject fault…
      </button>
      <form class="broadcast" onSubmit={(e) => {
        e.preventDefault();
        const n = picked.length || c.seats.length;
        void act(() => broadcast(c.id, picked, text)).then((ok) => {
          if (!ok) return;
          setText("");
          setSent(`sent to ${n} seat${n === 1 ? "" : "s"}`);
        });
      }}>
        <input value={text} maxLength={500} placeholder="message to the students" aria-label="message" data-testid="broadcast-text"
          onInput={(e) => { setText((e.target as HTMLInputElement).value); setSent(""); }} />
        <button type="submit" class="secondary" disabled={!text.trim()} data-testid="broadcast-send">Send</button>
        {sent ? <span class="hint broadcast-sent" role="status" data-testid="broadcast-sent">{sent}</span> : null}
      </form>
      {ending ? (
        <span class="confirm end-class" role="group" aria-label="confirm the end of the class">
          <span>End class '{c.id}'? Its machines and seat logins go; results, faults, traces and audit stay.</span>
          <button type="button" class="danger" data-testid="class-end-confirm" onClick={() => { setEnding(false); void act(() => endClass(c.id)); }}>
            Yes, end the class
          </button>
          <button type="button" class="secondary" data-testid="class-end-cancel" onClick={() => setEnding(false)}>Cancel</button>
        </span>
      ) : (
        <button type="button" class="danger end-class" data-testid="class-end" onClick={() => setEnding(true)}>
          End class
        </button>
      )}
    </div>
  );
}

export function Grid(props: { c: ClassInfo }) {
  const { c } = props;
  const link = gridLink.value;
  return (
    <Panel id="grid" title={`${c.title || c.id} · ${c.exercise}`}
      actions={<span class={`grid-link ${link}`} data-testid="grid-link" title="the grid's live connection">{link === "online" ? "live" : link}</span>}>
      <ClassBar c={c} />
      <RefusalLine refusal={actionRefusal.value} id="console-refusal" />
      <div class="seat-grid">
        {seats.value.map((s) => (
          <SeatTile key={s.n} seat={s} cid={c.id} user={c.seats.find((k) => k.n === s.n)?.user ?? ""} />
        ))}
        {!seats.value.length ? <p class="hint">waiting for the seats' status…</p> : null}
      </div>
    </Panel>
  );
}
