// One seat in the grid: who, the machine's state, its newest job error, who holds control,
// lag and speed over the last minute, progress and score, faults, seat time, and what the
// instructor can do with it. Fixed size and fixed rows: numbers change, the layout does not.
import type { AxisLine } from "../api/types";
import { freeze, gridTime, lowerHand, openHmi, selected, toggleSeat, type SeatLive } from "../state/classes";
import { fmt } from "../ui/format";
import { Sparkline } from "./Sparkline";
import { act, detailSeat, faultFor } from "./uiState";

const UNIT = { linear: "mm", rotary: "°", spindle: "rpm" } as const;
const FLOOR = { linear: 0.01, rotary: 0.01, spindle: 10 } as const; // scale floors: lag mm | °, speed rpm
const MAX_LINES = 3; // sparklines per tile (the lathe: X, Z, S1)
/** A joined seat whose student sent nothing for this long is idle (maybe stuck). */
export const IDLE_S = 120;

/** Seat time as m:ss (h:mm:ss past an hour). */
export function clock(s: number): string {
  const t = Math.max(0, Math.floor(s));
  const hh = Math.floor(t / 3600);
  const mm = Math.floor((t % 3600) / 60);
  const ss = String(t % 60).padStart(2, "0");
  return hh ? `${hh}:${String(mm).padStart(2, "0")}:${ss}` : `${mm}:${ss}`;
}

function AxisRow(props: { a: AxisLine; seat: SeatLive; now: number }) {
  const { a, seat, now } = props;
  const spindle = a.kind === "spindle";
  const value = spindle ? a.speed : a.lag;
  return (
    <div class="seat-axis" data-testid={`seat-axis-${a.name}`}>
      <span class="seat-axis-name">{a.name}</span>
      <span class="hint">{spindle ? "speed" : "lag"}</span>
      <Sparkline series={seat.history.get(a.name)} now={now} symmetric={!spindle} floor={FLOOR[a.kind]} bad={a.state === "ERROR"} />
      <span class="num seat-axis-value">
        {fmt(value, spindle ? 0 : 3)}&nbsp;{UNIT[a.kind]}
      </span>
    </div>
  );
}

/** `user`: the seat's login, so its control reads as the student's name. */
export function SeatTile(props: { seat: SeatLive; cid: string; user: string; plan: number }) {
  const { seat, cid, user, plan } = props;
  const f = seat.frame.value;
  const now = gridTime.value;
  // an empty seat's clock stands until its student logs in: "not joined", not "pause"
  const mode = !f.joined ? "not joined" : f.frozen ? "frozen" : f.mode;
  const idle = f.idle_s !== null && f.idle_s !== undefined && f.idle_s >= IDLE_S;
  const picked = selected.value.has(f.n);
  const cls = ["seat-tile", f.error_code ? "in-error" : "", f.frozen ? "frozen" : "", picked ? "picked" : ""].join(" ");
  return (
    <article class={cls} data-testid={`seat-${f.n}`} aria-label={`seat ${f.n}: ${f.student}`}>
      <header class="seat-head">
        <input type="checkbox" checked={picked} onChange={() => toggleSeat(f.n)} data-testid="seat-select" aria-label={`select seat ${f.n}`} />
        <b class="seat-n">{String(f.n).padStart(2, "0")}</b>
        <span class="seat-student" title={`${f.student} · ${f.machine}`} data-testid="seat-student">{f.student}</span>
        <span class={`seat-mode mode-${mode.replace(" ", "-")}`} data-testid="seat-mode">{mode}</span>
        {f.hand ? (
          <button type="button" class="seat-hand" data-testid="seat-hand" title={`asks for help${f.hand.text ? `: ${f.hand.text}` : ""} (click when seen to: lowers it)`}
            onClick={() => void act(() => lowerHand(f.machine))}>
            help
          </button>
        ) : null}
        {f.hand?.text ? <span class="seat-hand-text" data-testid="seat-hand-text" title={f.hand.text}>“{f.hand.text}”</span> : null}
        {f.progress >= 1 ? (
          <span class="seat-done" data-testid="seat-done" title="every check of its exercise has passed">done</span>
        ) : null}
        {idle ? (
          <span class="seat-idle" data-testid="seat-idle" title="no command from the student for this long">
            no input {clock(f.idle_s ?? 0)}
          </span>
        ) : null}
      </header>
      <div class="seat-line">
        <span data-testid="seat-channel" title="channel state">{f.channel}</span>
        <span class="seat-control" data-testid="seat-control" title={f.control ? `${f.control} holds control of the machine` : "nobody holds control"}>
          {f.control ? `◉ ${f.control === user ? f.student : f.control}` : "○ free"}
        </span>
      </div>
      <div class="seat-error" data-testid="seat-error" title={f.error ?? ""}>
        {f.error_code ? (
          <>
            <b>{f.error_code}</b> {f.error}
          </>
        ) : (
          <span class="hint">no job error</span>
        )}
      </div>
      <div class="seat-axes">
        {f.axes.slice(0, MAX_LINES).map((a) => (
          <AxisRow key={a.name} a={a} seat={seat} now={now} />
        ))}
      </div>
      <div class="seat-line">
        <span class="seat-progress" title={`checks that hold or held: ${Math.round(f.progress * 100)} %`}>
          <span class="bar" style={{ width: `${Math.round(f.progress * 100)}%` }} />
        </span>
        {plan > 1 ? (
          <span class="num seat-stage" title={`at exercise ${f.stage + 1} of the plan's ${plan}`}>
            ex&nbsp;<span data-testid="seat-stage">{f.stage + 1}/{plan}</span>
          </span>
        ) : null}
        <span class="num" data-testid="seat-score" title={plan > 1 ? `${fmt(f.score, 0)} in this exercise, ${fmt(f.total_score, 0)} over the plan` : "score"}>
          {fmt(plan > 1 ? f.total_score : f.score, 0)}&nbsp;pt
        </span>
        <span class={f.faults ? "seat-faults has" : "seat-faults"} data-testid="seat-faults" title="injected faults (active or armed)">
          ⚡{f.faults}
        </span>
        <span class="num" data-testid="seat-time" title="seat time (simulated)">{clock(f.seat_time_s)}</span>
      </div>
      <footer class="seat-actions">
        <button type="button" class="secondary" data-testid="seat-live" onClick={() => void act(() => openHmi(f.machine))}
          title="the seat's machine in the HMI: watch it live, take control">
          Live
        </button>
        <button type="button" class="secondary" data-testid="seat-detail" onClick={() => (detailSeat.value = f.n)} title="checks, hints, faults, snapshots, traces, commands">
          Detail
        </button>
        <button type="button" class="secondary" data-testid="seat-fault" onClick={() => (faultFor.value = [f.n])} title="inject a fault into this seat">
          Fault…
        </button>
        <button type="button" class="secondary" data-testid="seat-freeze" onClick={() => void act(() => freeze(cid, [f.n], !f.frozen))}>
          {f.frozen ? "Resume" : "Freeze"}
        </button>
      </footer>
    </article>
  );
}
