// The open class live: a bar of actions on the selected seats (or the whole class), counters
// (joined, in error, not joined, idle, done) that filter, an order, and one tile per seat,
// fed by the grid websocket.
import { useState } from "preact/hooks";
import type { ClassInfo, SeatFrame } from "../api/types";
import { broadcast, endClass, freeze, gridLink, moveSeatsOn, present, seats, selected } from "../state/classes";
import { machines } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { ResultLinks } from "./ResultLinks";
import { IDLE_S, SeatTile } from "./SeatTile";
import { act, actionRefusal, faultFor } from "./uiState";

/** Show one of the instructor's machines to every seat (watch only), or stop. */
function Presenting(props: { c: ClassInfo }) {
  const { c } = props;
  const own = machines.value.filter((m) => !c.seats.some((s) => s.machine === m.id));
  const [pick, setPick] = useState("");
  const chosen = pick || own[0]?.id || "";
  if (c.presenting) {
    return (
      <span class="presenting" data-testid="grid-presenting">
        ▣ presenting <b>{c.presenting}</b>{" "}
        <button type="button" class="secondary" data-testid="grid-present-stop" onClick={() => void act(() => present(c.id, null))}>Stop</button>
      </span>
    );
  }
  if (!own.length) return null;
  return (
    <span class="presenting">
      <select value={chosen} aria-label="machine to present" data-testid="grid-present-machine" onChange={(e) => setPick((e.target as HTMLSelectElement).value)}>
        {own.map((m) => <option key={m.id} value={m.id}>{m.id}</option>)}
      </select>{" "}
      <button type="button" class="secondary" data-testid="grid-present" title="every seat may watch it, read-only, until you stop"
        onClick={() => void act(() => present(c.id, chosen))}>
        Present to all
      </button>
    </span>
  );
}

function ClassBar(props: { c: ClassInfo }) {
  const { c } = props;
  const [text, setText] = useState("");
  const [sent, setSent] = useState(""); // "sent to N seats", until the next message is typed
  const [ending, setEnding] = useState(false); // asking whether to end the class
  const [moving, setMoving] = useState(false); // asking whether to move seats on
  const picked = [...selected.value].sort((a, b) => a - b);
  const notDone = seats.value
    .map((s) => s.frame.value)
    .filter((f) => (!picked.length || picked.includes(f.n)) && f.progress < 1)
    .map((f) => f.n);
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
      {c.exercises.length > 1 ? (
        moving ? (
          <span class="confirm" role="group" aria-label="confirm moving seats on">
            <span>
              Move {target} on to the next exercise? Each seat's score so far is kept; its machine powers on afresh.
              {notDone.length ? <b> Not every check passed yet: seat{notDone.length > 1 ? "s" : ""} {notDone.join(", ")}.</b> : null}
            </span>
            <button type="button" data-testid="grid-next-confirm" onClick={() => { setMoving(false); void act(() => moveSeatsOn(c.id, picked)); }}>
              Yes, move on
            </button>
            <button type="button" class="secondary" onClick={() => setMoving(false)}>Cancel</button>
          </span>
        ) : (
          <button type="button" class="secondary" data-testid="grid-next" onClick={() => setMoving(true)}
            title="the lesson plan's next exercise for the seats (a student moves on by themselves once every check passed)">
            Next exercise ▸
          </button>
        )
      ) : null}
      <Presenting c={c} />
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

type Show = "all" | "hand" | "error" | "waiting" | "idle" | "done";
type Order = "seat" | "error" | "score";
const SHOW_WORDS: Record<Show, string> = { all: "all", hand: "need help", error: "in error", waiting: "not joined", idle: "idle", done: "done" };

/** What a seat is, for the counters and the filter. */
function standing(f: SeatFrame): Exclude<Show, "all">[] {
  const out: Exclude<Show, "all">[] = [];
  if (f.hand) out.push("hand");
  if (f.error_code !== null) out.push("error");
  if (!f.joined) out.push("waiting");
  if (f.idle_s !== null && f.idle_s !== undefined && f.idle_s >= IDLE_S) out.push("idle");
  if (f.progress >= 1) out.push("done");
  return out;
}

/** Counters over the class, each a filter; and the order of the tiles (errors first keeps
 * them above the fold in a class of fifty). */
function GridHead(props: { show: Show; setShow: (s: Show) => void; order: Order; setOrder: (o: Order) => void }) {
  const frames = seats.value.map((s) => s.frame.value);
  const count = (k: Exclude<Show, "all">) => frames.filter((f) => standing(f).includes(k)).length;
  const joined = frames.filter((f) => f.joined).length;
  return (
    <div class="grid-head" data-testid="grid-head">
      <span class="hint">
        joined <b data-testid="grid-joined">{joined}</b> of {frames.length}
      </span>
      {(["all", "hand", "error", "waiting", "idle", "done"] as Show[]).map((k) => (
        <button key={k} type="button" class={`chip${props.show === k ? " on" : ""}${(k === "error" || k === "hand") && count(k) ? " bad" : ""}`}
          aria-pressed={props.show === k} data-testid={`grid-show-${k}`} onClick={() => props.setShow(k)}>
          {SHOW_WORDS[k]}{k === "all" ? "" : ` ${count(k)}`}
        </button>
      ))}
      <label class="hint">
        order{" "}
        <select value={props.order} data-testid="grid-order" onChange={(e) => props.setOrder((e.target as HTMLSelectElement).value as Order)}>
          <option value="seat">by seat</option>
          <option value="error">hands and errors first</option>
          <option value="score">lowest score first</option>
        </select>
      </label>
    </div>
  );
}

export function Grid(props: { c: ClassInfo }) {
  const { c } = props;
  const link = gridLink.value;
  const [show, setShow] = useState<Show>("all");
  const [order, setOrder] = useState<Order>("seat");
  const shown = seats.value
    .filter((s) => show === "all" || standing(s.frame.value).includes(show))
    .sort((a, b) => {
      const fa = a.frame.value;
      const fb = b.frame.value;
      if (order === "error")
        return Number(!!fb.hand) - Number(!!fa.hand) || Number(fb.error_code !== null) - Number(fa.error_code !== null) || fa.n - fb.n;
      if (order === "score") return fa.score - fb.score || fa.n - fb.n;
      return fa.n - fb.n;
    });
  return (
    <Panel id="grid" title={`${c.title || c.id} · ${c.exercises.join(" → ")}`}
      actions={
        <span class="grid-actions">
          <ResultLinks cid={c.id} />{" "}
          <span class={`grid-link ${link}`} data-testid="grid-link" title="the grid's live connection">{link === "online" ? "live" : link}</span>
        </span>
      }>
      <ClassBar c={c} />
      <GridHead show={show} setShow={setShow} order={order} setOrder={setOrder} />
      <RefusalLine refusal={actionRefusal.value} id="console-refusal" />
      <div class="seat-grid">
        {shown.map((s) => (
          <SeatTile key={s.n} seat={s} cid={c.id} user={c.seats.find((k) => k.n === s.n)?.user ?? ""} plan={c.exercises.length} />
        ))}
        {!seats.value.length ? <p class="hint">waiting for the seats' status…</p> : null}
        {seats.value.length && !shown.length ? <p class="hint">No seat is {SHOW_WORDS[show]}.</p> : null}
      </div>
    </Panel>
  );
}
