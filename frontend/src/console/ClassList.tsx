// The instructor's classes, running and ended: open one (its grid, or its debrief once ended).
import { chooseClass, classes, openClass } from "../state/classes";
import { Panel } from "../ui/Panel";
import { consoleView } from "./uiState";

const when = (unix: number) => new Date(unix * 1000).toLocaleString();

export function ClassList(props: { onNew: () => void }) {
  const running = classes.value.filter((c) => c.ended_unix === null);
  const ended = classes.value.filter((c) => c.ended_unix !== null);
  const item = (c: (typeof running)[number]) => (
    <li key={c.id}>
      <button type="button" class={c.id === openClass.value ? "class-item active" : "class-item"} data-testid={`class-${c.id}`}
        aria-pressed={c.id === openClass.value} onClick={() => { chooseClass(c.id); consoleView.value = "class"; }}>
        <b>{c.title || c.id}</b>
        <span class="hint">
          {c.exercises.join(" → ")} · {c.seats.length} {c.seats.length === 1 ? "seat" : "seats"} · {c.ended_unix === null ? `since ${when(c.created_unix)}` : `ended ${when(c.ended_unix)}`}
        </span>
      </button>
    </li>
  );
  return (
    <Panel id="classes" title="Classes" actions={<button type="button" data-testid="class-new" onClick={props.onNew}>New class</button>}>
      <div class="class-tools">
        <button type="button" class="secondary" data-testid="exercises-open" aria-pressed={consoleView.value === "exercises"}
          onClick={() => (consoleView.value = consoleView.value === "exercises" ? "class" : "exercises")}>
          Exercises
        </button>
        <button type="button" class="secondary" data-testid="roster-open" aria-pressed={consoleView.value === "roster"}
          onClick={() => (consoleView.value = consoleView.value === "roster" ? "class" : "roster")}>
          Roster
        </button>
      </div>
      <h3>Running</h3>
      {running.length ? <ul class="class-list">{running.map(item)}</ul> : <p class="hint">none</p>}
      <h3>Ended</h3>
      {ended.length ? <ul class="class-list">{ended.map(item)}</ul> : <p class="hint">none</p>}
    </Panel>
  );
}
