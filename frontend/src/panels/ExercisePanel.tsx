// The student's exercise on a class seat: the task, the checks as they stand on the live
// machine, progress and the time-weighted score, the hints (each costs points; asked first).
// Refreshed every 2 s while it shows. Faults are the instructor's: the service never sends them.
// Only the seat's own student takes hints; an instructor watching the seat reads which were
// taken (and their texts), with no button (a hint costs the student's points).
// A lesson plan runs its exercises in order: the panel says which one of how many, lists
// those done with their scores, and offers "Next exercise" once every check has passed (the
// instructor moves a seat on at any time).
// A finding check is answered, not measured: the student names the axis and the size (µm on
// a linear axis) in a few attempts; the answers given stay listed with their grades.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { CheckState, Exercise, FindingState, HintInfo } from "../api/types";
import { answerFinding, exercise, moveOn, raiseHand, refreshExercise, takeHint } from "../state/exercise";
import { Panel } from "../ui/Panel";
import { fmt } from "../ui/format";

const REFRESH_MS = 2000;
// as nc_sim/training/score.py LATE_FACTOR and FLOOR_WEIGHT (the explanation only; the service scores)
const LATE_FACTOR = 3;
const FLOOR_PCT = 50;

/** Seat time as m:ss (h:mm:ss from an hour). */
function clock(s: number): string {
  const t = Math.max(0, Math.floor(s));
  const [h, m, sec] = [Math.floor(t / 3600), Math.floor((t % 3600) / 60), t % 60];
  const pad = (n: number) => String(n).padStart(2, "0");
  return h ? `${h}:${pad(m)}:${pad(sec)}` : `${m}:${pad(sec)}`;
}

/** The task as paragraphs: blank lines part them; a file's hard line breaks inside one are
 * joined so the text flows at any width, except before list items. */
function paragraphs(task: string): string[] {
  return task
    .trim()
    .split(/\n\s*\n/)
    .map((p) => p.replace(/\n(?!\s*(?:[-*•]|\d+[.)])\s)/g, " "));
}

export function ExercisePanel() {
  useEffect(() => {
    void refreshExercise();
    const timer = setInterval(() => void refreshExercise(), REFRESH_MS);
    return () => clearInterval(timer);
  }, []);
  const ex = exercise.value;
  if (!ex) return <p class="hint">This machine is no class seat.</p>;
  const info = ex.exercise;
  const of = ex.plan.length > 1 ? ` ${ex.stage + 1} of ${ex.plan.length}` : "";
  return (
    <div class="exercise">
      <Panel title={`Exercise${of}: ${info.title}`} id="exercise">
        <p class="exercise-summary" data-testid="exercise-summary">{info.summary}</p>
        <div class="exercise-task" data-testid="exercise-task">
          {paragraphs(info.task).map((p, i) => (
            <p key={i}>{p}</p>
          ))}
        </div>
      </Panel>
      <div class="exercise-side">
        <Panel title="Progress and score" id="exercise-score">
          <Standing ex={ex} />
        </Panel>
        {ex.plan.length > 1 ? <Plan ex={ex} /> : null}
        {ex.takes_hints ? <Hand ex={ex} /> : null}
        <Panel title="Checks" id="exercise-checks">
          <ul class="checklist" data-testid="check-list">
            {ex.checks.map((c) => (
              <CheckRow key={c.id} check={c} mine={ex.takes_hints} />
            ))}
          </ul>
        </Panel>
        <Panel title="Hints" id="exercise-hints">
          {ex.hints.length && !ex.takes_hints ? (
            <p class="hint" data-testid="hints-read-only">
              {ex.student}'s hints (seat {ex.seat}): only the student takes them, each costs their points.
            </p>
          ) : null}
          {ex.hints.length ? (
            ex.hints.map((h) => <HintRow key={h.n} hint={h} mine={ex.takes_hints} done={ex.checks.every((c) => c.first_passed_s !== null)} />)
          ) : (
            <p class="hint">This exercise has no hints.</p>
          )}
        </Panel>
      </div>
    </div>
  );
}

/** The lesson plan: the exercises done (with their scores), this one, those to come; the
 * way on once every check has passed (asked first: there is no way back). */
function Plan({ ex }: { ex: Exercise }) {
  const [asking, setAsking] = useState(false);
  const [error, setError] = useState("");
  const last = ex.stage + 1 >= ex.plan.length;
  const allPassed = ex.checks.every((c) => c.first_passed_s !== null);
  const go = () =>
    moveOn().then(
      () => { setAsking(false); setError(""); },
      (e: unknown) => setError(e instanceof ApiError ? e.refusal.message : String(e)),
    );
  return (
    <Panel title="Lesson plan" id="exercise-plan">
      <ol class="plan-list" data-testid="plan-list">
        {ex.plan.map((title, k) => {
          const done = ex.done[k];
          const state = k < ex.stage ? "done" : k === ex.stage ? "now" : "later";
          return (
            <li key={k} class={`plan-${state}`} data-state={state}>
              {title}
              {done ? <span class="num"> · {fmt(done.score, 0)} of {fmt(done.max_points, 0)} points in {clock(done.seat_time_s)}</span> : null}
              {state === "now" ? <span class="hint"> · now</span> : null}
            </li>
          );
        })}
      </ol>
      {last ? (
        <p class="hint">This is the plan's last exercise.</p>
      ) : !ex.may_move_on ? (
        <p class="hint" data-testid="plan-wait">
          {allPassed ? "Your instructor moves you on." : "Once every check has passed you can move on to the next exercise (or your instructor moves you on)."}
        </p>
      ) : asking ? (
        <p role="alert" data-testid="plan-confirm">
          On to <b>{ex.plan[ex.stage + 1]}</b>? Your score here is kept; there is no way back. The machine powers on afresh.{" "}
          <button type="button" data-testid="plan-next-confirm" onClick={() => void go()}>Yes, next exercise</button>{" "}
          <button type="button" class="secondary" onClick={() => setAsking(false)}>Not yet</button>
        </p>
      ) : (
        <button type="button" data-testid="plan-next" onClick={() => setAsking(true)}>Next exercise ▸ {ex.plan[ex.stage + 1]}</button>
      )}
      {error ? <p class="refusal" role="alert">{error}</p> : null}
    </Panel>
  );
}

/** The student's raised hand: a word for the instructor, shown on their grid until lowered. */
function Hand({ ex }: { ex: Exercise }) {
  const [text, setText] = useState("");
  const [error, setError] = useState("");
  const run = (raised: boolean) =>
    raiseHand(raised, text).then(
      () => { setError(""); setText(""); },
      (e: unknown) => setError(e instanceof ApiError ? e.refusal.message : String(e)),
    );
  return (
    <Panel title="Help" id="exercise-hand">
      {ex.hand ? (
        <p data-testid="hand-raised">
          Your hand is up{ex.hand.text ? <> (“{ex.hand.text}”)</> : null}: your instructor sees it.{" "}
          <button type="button" class="secondary" data-testid="hand-lower" onClick={() => void run(false)}>Lower it</button>
        </p>
      ) : (
        <form class="row" onSubmit={(e) => { e.preventDefault(); void run(true); }}>
          <input value={text} maxLength={200} placeholder="what you need (optional)" aria-label="what you need" data-testid="hand-text"
            onInput={(e) => setText((e.target as HTMLInputElement).value)} />
          <button type="submit" class="secondary" data-testid="hand-raise">Raise hand</button>
        </form>
      )}
      {error ? <p class="refusal" role="alert">{error}</p> : null}
    </Panel>
  );
}

function Standing({ ex }: { ex: Exercise }) {
  const max = ex.checks.reduce((sum, c) => sum + c.points, 0);
  const counted = ex.checks.filter((c) => c.first_passed_s !== null).length;
  const hintCost = ex.hints.reduce((sum, h) => sum + (h.text !== null ? h.cost : 0), 0);
  const par = ex.exercise.par_time_s;
  return (
    <>
      <div class="exercise-stats">
        <Stat label="Score" id="exercise-score" value={fmt(ex.score, 0)} unit={`of ${fmt(max, 0)} points`} />
        <Stat label="Progress" id="exercise-progress" value={String(counted)} unit={`of ${ex.checks.length} checks`} />
        <Stat label="Seat time" id="exercise-time" value={clock(ex.seat_time_s)} unit={`par ${clock(par)}`} />
        <Stat label="Hints" id="exercise-hint-cost" value={hintCost ? `−${fmt(hintCost, 0)}` : "0"} unit="points" />
      </div>
      <progress class="exercise-bar" max={1} value={ex.progress} aria-label="progress" />
      <p class="hint">
        A check earns its full points when it first passes within the par time ({clock(par)} of seat time), then less
        and less, down to {FLOOR_PCT} % of its points at {LATE_FACTOR}× par ({clock(LATE_FACTOR * par)}). A check that
        passed once stays counted. Each hint you take costs its points (the score never goes below 0).
      </p>
    </>
  );
}

function Stat(props: { label: string; id: string; value: string; unit: string }) {
  return (
    <div class="stat">
      <span class="stat-label">{props.label}</span>
      <span>
        <b data-testid={props.id}>{props.value}</b> {props.unit}
      </span>
    </div>
  );
}

/** `mine`: the seat's own student, who answers its findings. */
function CheckRow({ check: c, mine }: { check: CheckState; mine: boolean }) {
  const state = c.passed ? "passed" : c.first_passed_s !== null ? "held" : "open";
  const label = { passed: "✓ passes now", held: "◐ held once", open: "○ not yet" }[state];
  return (
    <li class={`check ${state}`} data-testid={`check-${c.id}`} data-state={state}>
      <span class="check-state">{label}</span>
      <span class="check-text">{c.text}</span>
      <span class="check-points num">{fmt(c.points, 0)} points</span>
      {/* a finding's answers list their grades below: the newest is no second line here */}
      <span class="check-detail mono" data-testid="check-detail">
        {c.finding?.answers.length ? "" : c.detail}
      </span>
      <span class="check-when">
        {c.first_passed_s !== null ? `first passed at ${clock(c.first_passed_s)} seat time` : ""}
      </span>
      {c.finding ? <Finding check={c.id} finding={c.finding} mine={mine} passed={c.first_passed_s !== null} /> : null}
    </li>
  );
}

/** A size as the engineer says it: µm on a linear axis (its unit mm), the axis' unit else. */
function sizeOf(value: number, unit: string): string {
  return unit === "mm" ? `${fmt(value * 1000, 1)} µm` : `${fmt(value, 4)} ${unit}`;
}

function Finding(props: { check: string; finding: FindingState; mine: boolean; passed: boolean }) {
  const f = props.finding;
  const [axis, setAxis] = useState(f.axes[0] ?? "");
  const [text, setText] = useState("");
  const [busy, setBusy] = useState(false);
  const [error, setError] = useState("");
  const unit = f.units[f.axes.indexOf(axis)] ?? "mm";
  const shown = unit === "mm" ? "µm" : unit;
  const value = Number(text.replace(",", "."));
  const valid = text.trim() !== "" && Number.isFinite(value) && value > 0;
  const open = props.mine && !props.passed && f.attempts_left > 0;
  async function submit(e: Event): Promise<void> {
    e.preventDefault();
    if (!valid) return;
    setBusy(true);
    try {
      await answerFinding(props.check, axis, unit === "mm" ? value / 1000 : value);
      setText("");
      setError("");
    } catch (err) {
      setError(err instanceof ApiError ? err.message : String(err));
    } finally {
      setBusy(false);
    }
  }
  return (
    <div class="finding" data-testid="finding">
      {f.answers.length ? (
        <ol class="finding-answers" data-testid="finding-answers">
          {f.answers.map((a, i) => (
            <li key={i} class={a.passed ? "ok" : "wrong"}>
              <b>
                {a.passed ? "✓" : "✗"} {a.axis} {sizeOf(a.value, f.units[f.axes.indexOf(a.axis)] ?? "mm")}
              </b>{" "}
              <span class="hint">{a.detail}</span>
            </li>
          ))}
        </ol>
      ) : null}
      {open ? (
        <form class="finding-form" onSubmit={(e) => void submit(e)} aria-label={`answer ${props.check}`}>
          <label>
            Axis{" "}
            <select value={axis} onChange={(e) => setAxis((e.target as HTMLSelectElement).value)} data-testid="finding-axis">
              {f.axes.map((a) => (
                <option key={a} value={a}>
                  {a}
                </option>
              ))}
            </select>
          </label>
          <label>
            {f.fault} ({shown}){" "}
            <input
              class="num"
              inputMode="decimal"
              size={7}
              value={text}
              onInput={(e) => setText((e.target as HTMLInputElement).value)}
              data-testid="finding-value"
            />
          </label>
          <button type="submit" disabled={busy || !valid} data-testid="finding-submit">
            Answer ({f.attempts_left} {f.attempts_left === 1 ? "attempt" : "attempts"} left)
          </button>
        </form>
      ) : !props.passed && props.mine ? (
        <p class="hint">No attempts left.</p>
      ) : !props.mine && !f.answers.length ? (
        <p class="hint">Not answered yet: the student answers it ({f.attempts_left} attempts).</p>
      ) : null}
      {error ? <p class="inline-error" role="alert">{error}</p> : null}
    </div>
  );
}

/** `mine`: the seat's own student, who may take it (anyone else reads it, taken or not). */
function HintRow({ hint: h, mine, done }: { hint: HintInfo; mine: boolean; done: boolean }) {
  const [asking, setAsking] = useState(false);
  const [busy, setBusy] = useState(false);
  const [error, setError] = useState("");
  const cost = fmt(h.cost, 0);
  async function take(): Promise<void> {
    setBusy(true);
    try {
      await takeHint(h.n);
      setAsking(false);
      setError("");
    } catch (e) {
      setError(e instanceof ApiError ? e.message : String(e));
    } finally {
      setBusy(false);
    }
  }
  return (
    <div class="hint-row" data-testid={`hint-${h.n}`}>
      <div class="row">
        <b>Hint {h.n}</b>
        {h.text !== null ? (
          <span class="hint">taken: −{cost} points</span>
        ) : !mine ? (
          <span class="hint" data-testid="hint-not-taken">not taken ({cost} points)</span>
        ) : done ? (
          <span class="hint" data-testid="hint-not-needed">not needed: every check has passed</span>
        ) : asking ? (
          <span class="confirm" role="group" aria-label={`confirm hint ${h.n}`}>
            <span>
              Hint {h.n} takes {cost} points off your score. Show it?
            </span>
            <button type="button" data-testid="hint-confirm" disabled={busy} onClick={() => void take()}>
              Yes, show hint {h.n}
            </button>
            <button type="button" class="secondary" data-testid="hint-cancel" onClick={() => setAsking(false)}>
              Cancel
            </button>
          </span>
        ) : (
          <button type="button" class="secondary" data-testid="hint-show" onClick={() => setAsking(true)}>
            Show hint (costs {cost} points)
          </button>
        )}
      </div>
      {h.text !== null ? (
        <p class="hint-text" data-testid="hint-text">
          {h.text}
        </p>
      ) : null}
      {error ? <p class="inline-error" role="alert">{error}</p> : null}
    </div>
  );
}
