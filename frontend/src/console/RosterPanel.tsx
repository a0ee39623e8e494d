// The roster: every student kept across classes (a class made with "keep them on the roster"
// puts its named students here), and one student's record: each class they sat in, with
// their score in each exercise of its lesson plan.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal, StudentRecord } from "../api/types";
import { chooseClass } from "../state/classes";
import { forgetStudent, loadRoster, roster, studentRecord } from "../state/roster";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { clock } from "./SeatTile";
import { consoleView, detailSeat } from "./uiState";

const day = (unix: number | null) => (unix === null ? "—" : new Date(unix * 1000).toLocaleDateString());

export function RosterPanel() {
  const [filter, setFilter] = useState("");
  const [record, setRecord] = useState<StudentRecord | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const fail = (e: unknown) => setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
  useEffect(() => void loadRoster().catch(fail), []);
  const shown = roster.value.filter((s) => s.name.toLowerCase().includes(filter.trim().toLowerCase()));
  const open = (pid: number) => void studentRecord(pid).then(setRecord, fail);
  return (
    <Panel id="roster" title={`Roster (${roster.value.length} students)`}
      actions={<button type="button" class="secondary" data-testid="roster-close" onClick={() => (consoleView.value = "class")}>Close</button>}>
      <RefusalLine refusal={refusal} />
      <div class="roster-cols">
        <section>
          <input type="search" placeholder="find a student" aria-label="find a student" value={filter} data-testid="roster-filter"
            onInput={(e) => setFilter((e.target as HTMLInputElement).value)} />
          <table class="dense" data-testid="roster-list">
            <thead><tr><th>student</th><th class="num">classes</th><th>last</th></tr></thead>
            <tbody>
              {shown.map((s) => (
                <tr key={s.id} class={record?.student.id === s.id ? "picked" : ""}>
                  <td><button type="button" class="link" data-testid={`roster-${s.id}`} onClick={() => open(s.id)}>{s.name}</button></td>
                  <td class="num">{s.classes}</td>
                  <td>{day(s.last_unix)}</td>
                </tr>
              ))}
            </tbody>
          </table>
          {!roster.value.length ? (
            <p class="hint">Nobody yet: make a class with the students' names and tick "Keep them on the roster".</p>
          ) : null}
        </section>
        {record ? (
          <section data-testid="roster-record">
            <h3>{record.student.name}</h3>
            <p class="hint">
              on the roster since {day(record.student.created_unix)} (by {record.student.by}) · {record.sessions.length} class{record.sessions.length === 1 ? "" : "es"}
            </p>
            <table class="dense">
              <thead><tr><th>class</th><th>day</th><th class="num">seat</th><th>exercises</th><th class="num">score</th><th /></tr></thead>
              <tbody>
                {record.sessions.map((x) => (
                  <tr key={x.class_id} data-testid={`record-${x.class_id}`}>
                    <td>{x.title} <span class="hint">({x.class_id}, {x.instructor})</span></td>
                    <td>{day(x.created_unix)}{x.ended_unix === null ? " (running)" : ""}</td>
                    <td class="num">{x.seat}</td>
                    <td>
                      {x.stages.map((st) => (
                        <div key={st.exercise}>
                          {st.title}: <b>{fmt(st.score, 1)}</b> of {fmt(st.max_points, 0)} · {st.checks.filter((k) => k.first_passed_s !== null).length}/{st.checks.length} checks · {clock(st.seat_time_s)}
                        </div>
                      ))}
                    </td>
                    <td class="num"><b>{fmt(x.score, 1)}</b> of {fmt(x.max_points, 0)}</td>
                    <td>
                      <button type="button" class="link" onClick={() => { chooseClass(x.class_id); consoleView.value = "class"; detailSeat.value = x.seat; }}>
                        debrief
                      </button>
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
            <button type="button" class="danger" data-testid="roster-forget"
              onClick={() => confirm(`Take ${record.student.name} off the roster? Their results stay with their classes.`) &&
                void forgetStudent(record.student.id).then(() => setRecord(null), fail)}>
              Take off the roster
            </button>
          </section>
        ) : null}
      </div>
    </Panel>
  );
}
