// The instructor console: classes on the left (a new one, running and ended ones); the open
// class's live grid (or, ended, its seats for the debrief) with one seat's detail below; the
// fault form over it. It replaces the machine HMI under the same top bar.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ClassCreated, ClassInfo, Refusal } from "../api/types";
import { classes, deleteClass, loadClasses, loadExercises, openClass } from "../state/classes";
import { faultCatalogue } from "./faultCatalogue";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { ClassList } from "./ClassList";
import { CreateClass, SeatLinks } from "./CreateClass";
import { FaultForm } from "./FaultForm";
import { Grid } from "./Grid";
import { ResultLinks } from "./ResultLinks";
import { ExercisesPanel } from "./ExercisesPanel";
import { RosterPanel } from "./RosterPanel";
import { SeatDetail } from "./SeatDetail";
import { clock } from "./SeatTile";
import { act, consoleView, detailSeat, faultFor } from "./uiState";
import "./console.css";

/** An ended class's seats: results as they stood at the end, each seat's debrief. */
function EndedSeats(props: { c: ClassInfo }) {
  const plan = props.c.exercises.length;
  return (
    <Panel id="ended-seats" title={`${props.c.title || props.c.id} · ${props.c.exercises.join(" → ")} (ended)`}
      actions={
        <span>
          <ResultLinks cid={props.c.id} />{" "}
          <button type="button" class="danger" data-testid="class-delete"
            onClick={() => confirm(`Delete class '${props.c.id}'? Its results and debrief go (download them first); its id is free again.`) && void act(() => deleteClass(props.c.id))}>
            Delete
          </button>
        </span>
      }>
      <table class="dense">
        <thead>
          <tr>
            <th class="num">seat</th><th>student</th>{plan > 1 ? <th>reached</th> : null}<th class="num">progress</th>
            <th class="num">score{plan > 1 ? " (plan)" : ""}</th><th class="num">hints</th><th class="num">seat time</th><th />
          </tr>
        </thead>
        <tbody>
          {props.c.seats.map((s) => (
            <tr key={s.n} data-testid={`ended-seat-${s.n}`}>
              <td class="num">{s.n}</td>
              <td>{s.student}</td>
              {plan > 1 ? <td>exercise {s.stage + 1} of {plan}</td> : null}
              <td class="num" title="checks passed in the exercise reached">{Math.round(s.progress * 100)} %</td>
              <td class="num" data-testid="ended-score">{fmt(s.total_score, 1)}</td>
              <td class="num">{s.hints_taken + s.done.reduce((sum, d) => sum + d.hints_taken, 0)}</td>
              <td class="num">{clock(s.seat_time_s + s.done.reduce((sum, d) => sum + d.seat_time_s, 0))}</td>
              <td><button type="button" class="secondary" data-testid="seat-detail" onClick={() => (detailSeat.value = s.n)}>Debrief</button></td>
            </tr>
          ))}
        </tbody>
      </table>
    </Panel>
  );
}

export function Console() {
  const [creating, setCreating] = useState(false);
  const [created, setCreated] = useState<ClassCreated | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [dismissed, setDismissed] = useState(""); // the restart notice seen (class@time)
  useEffect(() => {
    void faultCatalogue().catch(() => undefined); // read ahead: the fault form opens filled (it says a failure)
    Promise.all([loadClasses(), loadExercises()]).catch((e: unknown) =>
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
  }, []);
  const c = classes.value.find((k) => k.id === openClass.value);
  useEffect(() => void (detailSeat.value = null), [c?.id]);
  const n = detailSeat.value;
  const classShown = consoleView.value === "class";
  return (
    <div class="console" data-testid="console">
      <aside class="console-side">
        <ClassList onNew={() => setCreating(true)} />
        <RefusalLine refusal={refusal} />
      </aside>
      <main class="console-main">
        {creating ? (
          <CreateClass onCancel={() => setCreating(false)} onCreated={(k) => { setCreating(false); setCreated(k); }} />
        ) : null}
        {/* keyed: a second class made before the first one's links were taken shows its own */}
        {created ? <SeatLinks key={created.info.id} created={created} onDone={() => setCreated(null)} /> : null}
        {/* told for the hour after the restart, until seen */}
        {c?.resumed && c.ended_unix === null && Date.now() / 1000 - c.resumed.at_unix < 3600 && dismissed !== `${c.id}@${c.resumed.at_unix}` ? (
          <p class="notice" role="status" data-testid="class-resumed">
            The service restarted at {new Date(c.resumed.at_unix * 1000).toLocaleTimeString()}; the class went on where it was:{" "}
            {c.resumed.seats} seats built again with their {c.resumed.faults} faults and {c.resumed.snapshots} snapshots, seat times,
            scores and hints kept.{" "}
            <button type="button" class="secondary" data-testid="class-resumed-dismiss" onClick={() => setDismissed(`${c.id}@${c.resumed!.at_unix}`)}>
              OK
            </button>
          </p>
        ) : null}
        {consoleView.value === "roster" ? <RosterPanel /> : null}
        {consoleView.value === "exercises" ? <ExercisesPanel /> : null}
        {c && classShown ? c.ended_unix === null ? <Grid c={c} /> : <EndedSeats c={c} /> : null}
        {!c && !creating && !created && classShown ? <p class="hint">Open a class on the left, or make a new one.</p> : null}
        {c && n !== null && classShown ? <SeatDetail key={`${c.id}/${n}`} c={c} n={n} /> : null}
        {c && faultFor.value !== null ? <FaultForm c={c} target={faultFor.value} /> : null}
      </main>
    </div>
  );
}
