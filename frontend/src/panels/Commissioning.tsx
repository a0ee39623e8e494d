// The commissioning assistants as a guided procedure: choose the assistant and the axis (the
// panel says what will happen, in the manual's words), preview it on a copy of the machine
// or run it on the machine itself (after confirming the motion; everyone sees its progress),
// read the figures, the lag and the proposal, Apply on trial (Keep / Revert in the trial
// bar), and run again to check.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { AssistResult, AxisStatus, Refusal } from "../api/types";
import { type Where, applyProposal, catalogue, liveRun, loadCatalogue, restartMachine, runAssistant } from "../state/assist";
import { commandBlocked, configureBlocked, may } from "../state/control";
import { numbers, paramsVersion, trial } from "../state/params";
import { me } from "../state/auth";
import { lockedAssistants } from "../state/exercise";
import { machineId, online, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { AssistField } from "./AssistField";
import { AssistResultView } from "./AssistResultView";
import { LiveProgress } from "./LiveProgress";
import { LOOP_GAIN_START, LoopGainFields, checkLoopGain, describeLoopGain, loopGainErrors, loopGainRequest, useAxisNow } from "./LoopGainSetup";
import { perSecond } from "../ui/units";
import { codeSpans } from "../ui/codeSpans";
import { SchemaFields, axesFor, formBody, formFields, startTexts } from "./SchemaForm";
import { DrivePlan, circleProblem } from "./DrivePlan";

// the assistants with a guided form of their own here; every other experiment of the
// catalogue gets the form its request schema describes
type Guided = "multi-gain" | "sign-check" | "loop-gain";
const GUIDED = new Set<string>(["multi-gain", "sign-check", "loop-gain"]);

/** The limits of api/assist.py, checked as the engineer types (the service checks again). */
interface Inputs {
  feed: string; // mm/min (°/min) of the multi_gain run
  speed: string; // rpm of a spindle's multi_gain run
  window: string; // s
  direction: 1 | -1;
  distance: string; // mm (°) of the sign check
  signFeed: string; // mm/min (°/min) of the sign check
  observed: "" | "1" | "-1"; // "": the simulated plant's
}

const START: Inputs = { feed: "200", speed: "100", window: "1", direction: 1, distance: "1", signFeed: "100", observed: "" };

/** The number in `text` within (lo, hi] or [lo, hi], or why not. */
function inRange(text: string, what: string, lo: number, hi: number, unit: string, loOpen: boolean): number | string {
  const v = Number(text.trim());
  if (text.trim() === "" || !Number.isFinite(v)) return `${what}: a number is needed`;
  if ((loOpen ? v <= lo : v < lo) || v > hi) return `${what}: ${loOpen ? `> ${lo}` : `≥ ${lo}`} and ≤ ${hi} ${unit}`;
  return v;
}

/** Per input: its value, or an error to show beside it. */
function checked(inp: Inputs, unit: string) {
  return {
    feed: inRange(inp.feed, "feed", 0, 1e6, `${unit}/min`, true),
    speed: inRange(inp.speed, "speed", 0, 1e5, "rpm", true),
    window: inRange(inp.window, "window", 0.2, 30, "s", false),
    distance: ((v) => (v === 0 ? "distance: not 0" : v))(inRange(inp.distance, "distance", -100, 100, unit, false)),
    signFeed: inRange(inp.signFeed, "feed", 0, 1e5, `${unit}/min`, true),
  };
}

const n1 = (v: number) => String(+v.toPrecision(3));

/** The assistants of the Drive tuning workspace: the drive's own measurements. */
export const DRIVE_ASSISTANTS: readonly string[] = ["frequency-response", "autotune", "step-response", "drive-trace", "circle"];

/** The assistants' panel: the NC's commissioning (by default), or the drive's measurements
 * (`drive`: the Drive tuning workspace). */
export function Commissioning(props: { drive?: boolean }) {
  const axes = status.value?.axes ?? [];
  const drive = !!props.drive;
  const assistants = catalogue.value.filter((a) => a.kind === "experiment" && DRIVE_ASSISTANTS.includes(a.name) === drive);
  const [name, setName] = useState<string>(drive ? DRIVE_ASSISTANTS[0] : "multi-gain");
  const info = assistants.find((a) => a.name === name);
  const locked = lockedAssistants.value.includes(name);
  const fields = info ? formFields(info.request) : [];
  const [texts, setTexts] = useState<Record<string, string>>({});
  const guided = GUIDED.has(name);
  const [axisName, setAxisName] = useState("X");
  const [inp, setInp] = useState<Inputs>(START);
  const [result, setResult] = useState<AssistResult | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busySince, setBusySince] = useState<number | null>(null);
  const [elapsed, setElapsed] = useState(0);
  const [applied, setApplied] = useState(false);
  const [confirming, setConfirming] = useState(false); // the live run's motion, to confirm
  const [where, setWhere] = useState<Where>("copy"); // of the run going on or shown
  const [restarted, setRestarted] = useState(false); // since the proposal was applied
  const [kv, setKv] = useState<number | null>(null); // 1/s, for the run's expected duration

  const choices = axesFor(fields, axes);
  const ax: AxisStatus | undefined = choices.find((a) => a.name === axisName) ?? choices[0];
  const spindle = ax?.kind === "spindle";
  const unit = ax?.unit ?? "mm";
  const values = checked(inp, unit);
  const used =
    name === "multi-gain" ? [spindle ? values.speed : values.feed, values.window] : [values.distance, values.signFeed];
  // loop gain (LoopGainSetup.tsx): its own inputs, checked as typed
  const [lg, setLg] = useState(LOOP_GAIN_START);
  const lgValues = checkLoopGain(lg);
  const axNow = useAxisNow(ax);
  const form = formBody(fields, texts, ax?.name ?? "");
  const errors = !guided
    ? [...Object.values(form.errors), ...(name === "circle" && circleProblem(form.body) ? [circleProblem(form.body)] : [])]
    : name === "loop-gain"
      ? loopGainErrors(lgValues)
      : used.filter((v): v is string => typeof v === "string");
  const mayAssist = may("assist");
  const busy = busySince !== null;
  const blocked = configureBlocked.value;

  useEffect(() => void loadCatalogue(), []);
  useEffect(() => setTexts(startTexts(fields)), [name, assistants.length]);
  useEffect(() => {
    // a result belongs to its machine, assistant and axis
    setResult(null);
    setRefusal(null);
    setApplied(false);
    setConfirming(false);
  }, [machineId.value, name, ax?.name]);
  useEffect(() => {
    if (!ax || !machineId.value) return;
    numbers("axis", ax.name).then(
      (m) => setKv(((m.get(`getriebe[${Math.max(0, (ax.gear ?? 1) - 1)}].kv`) ?? NaN) as number) / 100),
      () => setKv(null),
    );
  }, [machineId.value, ax?.name, paramsVersion.value]);
  useEffect(() => {
    if (busySince === null) return;
    const id = setInterval(() => setElapsed((performance.now() - busySince) / 1000), 100);
    return () => clearInterval(id);
  }, [busySince]);

  async function run(at: Where) {
    if (!ax || errors.length) return;
    setConfirming(false);
    setWhere(at);
    setResult(null); // the old result is not this run's
    setApplied(false);
    setBusySince(performance.now());
    setElapsed(0);
    setRefusal(null);
    try {
      const r = !guided
        ? await runAssistant(name, form.body, at)
        : name === "loop-gain"
          ? await runAssistant("loop-gain", loopGainRequest(ax.name, lgValues), "copy")
          : name === "multi-gain"
          ? await runAssistant("multi-gain", {
              axis: ax.name,
              feed_mm_min: spindle ? null : (values.feed as number),
              speed_rpm: spindle ? (values.speed as number) : null,
              window_s: values.window as number,
              direction: inp.direction,
            }, at)
          : await runAssistant("sign-check", {
              axis: ax.name,
              distance: values.distance as number,
              feed_mm_min: values.signFeed as number,
              observed: inp.observed === "" ? null : (Number(inp.observed) as 1 | -1),
            }, at);
      setResult(r);
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
    } finally {
      setBusySince(null);
    }
  }

  async function apply() {
    if (!result) return;
    setRefusal(null);
    try {
      await applyProposal(result.assistant, result.changes);
      setApplied(true);
      setRestarted(false);
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: e instanceof Error ? e.message : String(e), problems: [] });
    }
  }

  async function restart() {
    setRefusal(null);
    try {
      await restartMachine();
      setRestarted(true);
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
    }
  }

  const set = (patch: Partial<Inputs>) => setInp({ ...inp, ...patch });
  const field = (key: keyof Inputs, label: string, u: string, testid: string) => {
    const err = (values as Record<string, number | string>)[key];
    return (
      <AssistField label={label} unit={u} testid={testid} value={inp[key] as string} disabled={busy}
        error={typeof err === "string" ? err : null} onInput={(v) => set({ [key]: v })} />
    );
  };

  const step = !result ? (busy || confirming ? 2 : 1) : applied ? 4 : 3;
  const onTrial = !!trial.value;
  const live = liveRun.value;
  const liveBlocked =
    commandBlocked.value ||
    (status.value?.emergency_stop ? "emergency stop: release it and reset first" : "") ||
    (status.value?.simulation.mode === "pause" ? "the machine is paused: run it (Simulation) first" : "") ||
    (live ? `${live.name} runs on the machine (${live.by})` : "");
  return (
    <Panel title={drive ? "Drive tuning: frequency response and steps" : "Commissioning assistants"} id={drive ? "drive" : "assist"}>
      <ol class="assist-steps" aria-label="steps">
        {["Choose", "Preview on a copy or run on the machine", "Read the result", drive ? "Change, measure again, compare" : "Apply on trial, run again"].map((s, i) => (
          <li key={s} class={i + 1 === step ? "active" : i + 1 < step ? "done" : ""}>
            {s}
          </li>
        ))}
      </ol>
      {!mayAssist ? (
        <p class="assist-readonly" role="status" data-testid="assist-readonly">
          Read-only: running an assistant needs the role operator (you are {me.value?.role ?? "not logged in"}).
        </p>
      ) : null}
      {locked ? (
        <p class="assist-readonly" role="status" data-testid="assist-locked">
          🔒 Your exercise locks the {info?.title ?? name} assistant: work it out by hand (the scope and the parameters are yours).
        </p>
      ) : null}
      <div class="assist">
        <div class="assist-setup">
          <fieldset class="assist-choice" disabled={busy}>
            <legend>Assistant</legend>
            {assistants.map((a) => (
              <label key={a.name}>
                <input type="radio" name="assistant" data-testid={`assist-pick-${a.name}`} checked={a.name === name}
                  onChange={() => setName(a.name)} />
                {a.title} <span class="hint">({a.section})</span>
                {lockedAssistants.value.includes(a.name) ? <span class="locked" title="your exercise locks it: work it out by hand"> 🔒</span> : null}
              </label>
            ))}
          </fieldset>
          {fields.some((f) => f.kind === "axis") || guided ? (
          <label class="assist-field">
            <span>Axis</span>
            <select data-testid="assist-axis" value={ax?.name} disabled={busy}
              onChange={(e) => setAxisName((e.target as HTMLSelectElement).value)}>
              {choices.map((a) => (
                <option key={a.name} value={a.name}>
                  {a.name} ({a.kind})
                </option>
              ))}
            </select>
          </label>
          ) : null}
          {!guided ? (
            <SchemaFields fields={fields} texts={texts} errors={form.errors} disabled={busy} testid="assist-in"
              set={(k, v) => setTexts({ ...texts, [k]: v })} />
          ) : name === "multi-gain" ? (
            <>
              {spindle
                ? field("speed", "Speed", "rpm", "assist-speed")
                : field("feed", "Feed", `${unit}/min`, "assist-feed")}
              {field("window", "Average the lag over", "s", "assist-window")}
              <label class="assist-field">
                <span>Direction</span>
                <select data-testid="assist-direction" value={String(inp.direction)} disabled={busy}
                  onChange={(e) => set({ direction: Number((e.target as HTMLSelectElement).value) as 1 | -1 })}>
                  <option value="1">+ (positive)</option>
                  <option value="-1">− (negative)</option>
                </select>
              </label>
            </>
          ) : name === "loop-gain" ? (
            <LoopGainFields inp={lg} set={setLg} values={lgValues} busy={busy} />
          ) : (
            <>
              {field("distance", "Distance", unit, "assist-distance")}
              {field("signFeed", "Feed", `${unit}/min`, "assist-sign-feed")}
              <label class="assist-field">
                <span>The machine moved</span>
                <select data-testid="assist-observed" value={inp.observed} disabled={busy}
                  onChange={(e) => set({ observed: (e.target as HTMLSelectElement).value as Inputs["observed"] })}>
                  <option value="">as the simulated plant moves</option>
                  <option value="1">+ as commanded</option>
                  <option value="-1">− the other way</option>
                </select>
              </label>
            </>
          )}
          {ax ? <p class="assist-what" data-testid="assist-what">{!guided ? codeSpans(info?.text ?? "") : name === "loop-gain" ? describeLoopGain(ax, lgValues, axNow) : describe(name as Guided, ax, inp, values, kv, busy ? where : confirming ? "machine" : "copy")}</p> : null}
          {ax && drive ? <DrivePlan name={name} axis={ax} body={form.body} /> : null}
          <div class="row">
            <button type="button" data-testid="assist-run" disabled={!online.value || !ax || busy || errors.length > 0 || !mayAssist || locked}
              title={mayAssist ? "a copy of the machine, in simulated time: nothing moves" : `a user in the role ${me.value?.role ?? ""} may not run assistants`}
              onClick={() => void run("copy")}>
              {busy && where === "copy" ? "Running…" : applied && name === "multi-gain" ? "Preview again to check" : result ? "Preview again" : "Preview on a copy"}
            </button>
            <button type="button" class="secondary" data-testid="assist-run-live"
              disabled={!online.value || !ax || busy || errors.length > 0 || !!liveBlocked || confirming || !info?.live || locked}
              title={!info?.live ? "it runs on copies of the machine only" : liveBlocked || "the machine itself moves: you confirm the motion first"} onClick={() => setConfirming(true)}>
              Run on the machine…
            </button>
            {busy && where === "copy" ? (
              <span class="assist-busy" role="status" data-testid="assist-busy">
                <span class="spinner" aria-hidden="true" /> running on a copy of the machine… {elapsed.toFixed(1)} s
              </span>
            ) : null}
          </div>
          {liveBlocked && !busy && !live ? (
            <span class="hint" data-testid="assist-live-blocked">
              On the machine: {liveBlocked}
            </span>
          ) : null}
          {confirming && ax ? (
            <div class="assist-confirm" role="alertdialog" aria-labelledby="assist-confirm-title" data-testid="assist-confirm">
              <b id="assist-confirm-title">The machine will move</b>
              {drive ? (
                <DrivePlan name={name} axis={ax} body={form.body} live />
              ) : (
                <p>{guided ? describe(name as Guided, ax, inp, values, kv, "machine") : codeSpans(info?.text ?? "")}</p>
              )}
              <p class="hint">Keep clear of the machine. The E-stop and Cancel end the run at once.</p>
              <div class="row">
                <button type="button" data-testid="assist-confirm-live" onClick={() => void run("machine")} disabled={!!liveBlocked}>
                  {name === "circle" ? "Run the circle now" : `Move ${ax.name} now`}
                </button>
                <button type="button" class="secondary" data-testid="assist-confirm-back" onClick={() => setConfirming(false)}>
                  Back
                </button>
              </div>
            </div>
          ) : null}
          <LiveProgress />
          <RefusalLine refusal={refusal} id="assist-refusal" />
        </div>
        <div class="assist-out">
          {result ? (
            <>
              <p class="hint" data-testid="assist-where">
                {where === "machine" ? "Measured on the machine itself." : "Measured on a copy of the machine (simulated time); the machine did not move."}
              </p>
              <AssistResultView result={result} spindle={spindle} live={where === "machine"} />
              <div class="row apply-bar">
                <button type="button" data-testid="assist-apply"
                  disabled={!online.value || !result.changes.length || onTrial || !!blocked || busy}
                  title={blocked || (onTrial ? "Keep or Revert the values on trial first" : "")} onClick={() => void apply()}>
                  Apply on trial
                </button>
                {applied ? (
                  <span class="hint" data-testid="assist-applied">
                    Applied: Keep or Revert in the trial bar above.
                    {!guided
                      ? " Run again to check."
                      : name === "loop-gain"
                      ? " Run again to see the sweep around the new kv."
                      : name === "multi-gain"
                      ? " Run again to check: k must now equal kv (f ≈ 1)."
                      : restarted
                        ? " Restarted: the new signs are in force. Run again to check."
                        : " The signs take effect at the machine's restart (the copy's too): restart, then run again to check."}
                  </span>
                ) : null}
                {applied && name === "sign-check" && !restarted ? (
                  <button type="button" data-testid="assist-restart" disabled={!online.value || !!commandBlocked.value || busy}
                    title={commandBlocked.value || "power off and on: every stored value in force, the axes at rest, not homed"}
                    onClick={() => void restart()}>
                    Restart the machine
                  </button>
                ) : !applied && blocked ? (
                  <span class="hint" data-testid="assist-apply-blocked">
                    {blocked}
                  </span>
                ) : null}
              </div>
            </>
          ) : (
            <p class="hint assist-empty">{busy ? "The result follows when the run ends." : "Choose, check what it will do, Run."}</p>
          )}
        </div>
      </div>
    </Panel>
  );
}

/** What the run will do, in the manual's words, with the motion it needs. */
function describe(
  name: Guided,
  ax: AxisStatus,
  inp: Inputs,
  values: ReturnType<typeof checked>,
  kv: number | null,
  where: Where,
): string {
  const unit = ax.unit;
  const copy =
    where === "copy"
      ? "on a copy of the machine, in simulated time; the live machine does not move."
      : "on the machine itself, in its time (paused meanwhile, it waits; fast, it runs fast).";
  if (name === "sign-check") {
    const d = typeof values.distance === "number" ? values.distance : null;
    const f = typeof values.signFeed === "number" ? values.signFeed : null;
    const motion = d !== null && f !== null ? `${ax.name} moves ${d > 0 ? "+" : ""}${n1(d)} ${unit} at ${n1(f)} ${unit}/min ` : `${ax.name} moves a short distance `;
    return (
      `${motion}${copy} A wrong sign of the manipulated variable (vz_stellgr) or of the actual value (vz_istw) ` +
      "turns the loop into positive feedback: the actual position runs away, the servo is switched off at once, " +
      "before lag monitoring (lag_max) trips (004 §3.5)."
    );
  }
  const w = typeof values.window === "number" ? values.window : 1;
  // as nc_sim/assist/experiments.py: the ramp, five time constants at a third of kv to
  // settle, the window, and a second more recorded
  const settle = kv && Number.isFinite(kv) && kv > 0 ? 15 / kv : null;
  const runS = settle !== null ? 3 + settle + Math.max(w, 0.2) : null;
  const dir = inp.direction > 0 ? "+" : "−";
  const formula =
    `The lag s is averaged at constant speed once the loop has settled (at least ${n1(w)} s); ` +
    "k = v/s, f = kv/k (the manual's (kv/100)/k with kv in 0.01/s), and multi_gain · f with kv / f are proposed (004 §3.6.2).";
  // the move goes on a second past the recording (its target is v · (recording + 1 s))
  const moveS = runS !== null ? runS + 1 : null;
  const about = moveS !== null ? ` for about ${n1(moveS)} s` : "";
  if (ax.kind === "spindle") {
    const sp = typeof values.speed === "number" ? `${n1(values.speed)} rpm` : "the speed";
    // at speed: settling, the window and 1.5 s more recorded, then M5
    const turn = settle !== null ? ` for about ${n1(settle + Math.max(w, 0.2) + 1.5)} s` : "";
    return `${ax.name} runs up to ${sp} (${dir}), then turns position-controlled at constant speed${turn} and stops (M5) ${copy} ${formula}`;
  }
  const feed = typeof values.feed === "number" ? values.feed : null;
  const travel = feed !== null && moveS !== null ? ` (about ${dir}${n1(perSecond(feed) * moveS)} ${unit})` : "";
  return `${ax.name} moves at ${feed !== null ? `${n1(feed)} ${unit}/min` : "the feed"} (${dir}) at constant speed${about}${travel} ${copy} ${formula}`;
}
