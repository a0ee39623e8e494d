// Exercises in the console: the shipped and uploaded ones, and the author's editor. An
// exercise is its TOML file (exercises/README format): open one (a shipped one to save under
// another id), edit it, try it — checked as an upload is, then its seat run untouched on a copy
// with its checks judged — and save it. The try-out says what would make it a poor exercise.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { ExerciseDryRun, ExerciseInfo, Refusal } from "../api/types";
import { exercises, loadExercises } from "../state/classes";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { consoleView } from "./uiState";

const TRIES_S = [5, 20, 60] as const;

/** A new exercise to start from: every part of the format once, ready to try. */
const NEW_EXERCISE = `id = "my-exercise"
title = "My exercise"
summary = "One or two sentences for the list of exercises."
par_time_s = 600
machine = "demo"
task = """
What the student reads: the situation, what to find or set, when it is done.
"""

[[faults]]                 # what is wrong with the seat's machine (see the fault form)
kind = "drive_gain_wrong"
axis = "X"
factor = 0.5

[[vary]]                   # each seat its own number: neighbours cannot copy
key = "faults[0].factor"
min = 0.4
max = 0.6
step = 0.01

[[hints]]
text = "A hint that helps without giving the answer away."
cost = 10

[[checks]]
id = "gain"
text = "X's measured gain at constant speed is within 1 % of kv"
points = 100
kind = "gain"
axis = "X"
within_pct = 1.0
keep_kv = true
`;

const fail = (e: unknown): Refusal => (e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });

export function ExercisesPanel() {
  const [text, setText] = useState(NEW_EXERCISE);
  const [opened, setOpened] = useState<ExerciseInfo | null>(null);
  const [seconds, setSeconds] = useState<number>(TRIES_S[1]);
  const [dry, setDry] = useState<ExerciseDryRun | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const [saved, setSaved] = useState("");
  useEffect(() => void loadExercises().catch((e: unknown) => setRefusal(fail(e))), []);
  const open = (x: ExerciseInfo) =>
    void http.get<string>(`/api/exercises/${x.id}/text`).then(
      (t) => { setText(t); setOpened(x); setDry(null); setRefusal(null); setSaved(""); },
      (e: unknown) => setRefusal(fail(e)),
    );
  const run = async (what: () => Promise<void>) => {
    setBusy(true);
    try {
      await what();
      setRefusal(null);
    } catch (e) {
      setRefusal(fail(e));
      setDry(null);
    } finally {
      setBusy(false);
    }
  };
  const tryIt = () => run(async () => setDry(await http.post<ExerciseDryRun>("/api/exercises/dry-run", { text, seconds })));
  const save = () =>
    run(async () => {
      const info = await http.post<ExerciseInfo>("/api/exercises", { text });
      await loadExercises();
      setOpened(info);
      setSaved(`saved as '${info.id}': it is in the class form's list`);
    });
  const remove = (x: ExerciseInfo) =>
    confirm(`Remove exercise '${x.id}'? Classes that ran it keep their copy.`) &&
    void run(async () => {
      await http.del(`/api/exercises/${x.id}`);
      await loadExercises();
      setOpened(null);
      setText(NEW_EXERCISE);
    });
  const shipped = opened?.source.startsWith("shipped") ?? false;
  return (
    <Panel id="exercises" title="Exercises"
      actions={<button type="button" class="secondary" data-testid="exercises-close" onClick={() => (consoleView.value = "class")}>Close</button>}>
      <div class="exercises-cols">
        <section>
          <button type="button" data-testid="exercise-new" onClick={() => { setText(NEW_EXERCISE); setOpened(null); setDry(null); setSaved(""); }}>
            New exercise
          </button>
          <ul class="plain exercise-list" data-testid="exercise-list">
            {[...exercises.value].sort((a, b) => a.title.localeCompare(b.title)).map((x) => (
              <li key={x.id} class={opened?.id === x.id ? "picked" : ""}>
                <button type="button" class="link" data-testid={`exercise-open-${x.id}`} onClick={() => open(x)}>{x.title}</button>
                <div class="hint">{x.id} · {x.source}</div>
              </li>
            ))}
          </ul>
        </section>
        <section>
          <p class="hint">
            {opened ? <>Editing <b>{opened.id}</b> ({opened.source}){shipped ? ": a shipped exercise stays; give the copy an id of its own to save it" : ""}.</> : "A new exercise."}{" "}
            The file is TOML: <code>[[start]]</code> values, <code>[[faults]]</code>, <code>[[vary]]</code> per-seat numbers,{" "}
            <code>locked_assistants</code>, <code>[[hints]]</code> and <code>[[checks]]</code>.
          </p>
          <textarea class="mono exercise-text" rows={26} spellcheck={false} value={text} aria-label="exercise file" data-testid="exercise-text"
            onInput={(e) => { setText((e.target as HTMLTextAreaElement).value); setSaved(""); setRefusal(null); }} />
          <div class="row">
            <button type="button" data-testid="exercise-try" disabled={busy} onClick={() => void tryIt()}>
              {busy ? "Trying…" : "Try it on a copy"}
            </button>
            <select value={seconds} aria-label="how long the seat runs" data-testid="exercise-try-seconds" onChange={(e) => setSeconds(Number((e.target as HTMLSelectElement).value))}>
              {TRIES_S.map((s) => <option key={s} value={s}>{s} s untouched</option>)}
            </select>
            <button type="button" class="secondary" data-testid="exercise-save" disabled={busy} onClick={() => void save()}>Save</button>
            {opened && !shipped ? (
              <button type="button" class="danger" data-testid="exercise-remove" disabled={busy} onClick={() => remove(opened)}>Remove</button>
            ) : null}
            {saved ? <span class="hint" role="status" data-testid="exercise-saved">{saved}</span> : null}
          </div>
          <RefusalLine refusal={refusal} id="exercise-refusal" />
          {dry ? <DryRunView dry={dry} /> : null}
        </section>
      </div>
    </Panel>
  );
}

function DryRunView({ dry }: { dry: ExerciseDryRun }) {
  return (
    <div class="dry-run" data-testid="exercise-dry-run">
      <h3>Tried: {dry.info.title} — seat 1 untouched for {fmt(dry.seconds, 0)} s</h3>
      {dry.warnings.length ? (
        <ul class="warnings" data-testid="dry-warnings">
          {dry.warnings.map((w) => <li key={w}>⚠ {w}</li>)}
        </ul>
      ) : (
        <p class="ok" data-testid="dry-ok">✓ Nothing gives its points away; the checks wait for the student.</p>
      )}
      <table class="dense" data-testid="dry-checks">
        <thead><tr><th>check</th><th class="num">points</th><th>untouched</th><th>measured</th></tr></thead>
        <tbody>
          {dry.checks.map((k) => (
            <tr key={k.id} class={k.first_passed_s !== null ? "bad" : ""}>
              <td>{k.text}</td>
              <td class="num">{fmt(k.points, 0)}</td>
              <td>{k.first_passed_s !== null ? `passed at ${fmt(k.first_passed_s, 1)} s` : "not passed"}</td>
              <td class="mono">{k.detail}</td>
            </tr>
          ))}
        </tbody>
      </table>
      <p class="hint">
        {Object.keys(dry.values).length
          ? `Seat 1's own numbers: ${Object.entries(dry.values).map(([k, v]) => `${k} = ${fmt(v, 4)}`).join(", ")}. `
          : ""}
        {dry.job_errors.length
          ? `Job errors with nobody at the machine: ${dry.job_errors.map((j) => `${j.code} at ${fmt(j.t_s, 1)} s (${j.message})`).join("; ")}.`
          : "No job error with nobody at the machine."}{" "}
        {dry.info.faults} fault{dry.info.faults === 1 ? "" : "s"} at start · {dry.info.hints.length} hints · par {fmt(dry.info.par_time_s, 0)} s
        {dry.info.locked_assistants.length ? ` · locks ${dry.info.locked_assistants.join(", ")}` : ""}
      </p>
    </div>
  );
}
