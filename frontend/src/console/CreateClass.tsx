// A new class: the exercise (what it asks, its checks and hints, how many faults it injects),
// how many seats, the students' names; then each seat's one-time login link, shown this once.
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ClassCreated, Refusal, SeatLink } from "../api/types";
import { chooseClass, createClass, exercises, newLink } from "../state/classes";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";

const MAX_SEATS = 60; // api/classes.py MAX_SEATS

export function CreateClass(props: { onCreated: (c: ClassCreated) => void; onCancel: () => void }) {
  const [id, setId] = useState("");
  const [title, setTitle] = useState("");
  const [exercise, setExercise] = useState(exercises.value[0]?.id ?? "");
  const [seats, setSeats] = useState(2);
  const [students, setStudents] = useState("");
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const ex = exercises.value.find((e) => e.id === exercise) ?? exercises.value[0];
  const names = students.split("\n").map((s) => s.trim()).filter(Boolean);
  async function submit(e: Event) {
    e.preventDefault();
    setBusy(true);
    try {
      const created = await createClass({ id, title, exercise: ex?.id ?? "", seats, students: names });
      setRefusal(null);
      chooseClass(created.info.id);
      props.onCreated(created);
    } catch (err) {
      setRefusal(err instanceof ApiError ? err.refusal : { message: String(err), problems: [] });
    } finally {
      setBusy(false);
    }
  }
  const str = (set: (v: string) => void) => (e: Event) => set((e.target as HTMLInputElement).value);
  return (
    <Panel id="class-create" title="New class">
      <form class="class-form" onSubmit={(e) => void submit(e)}>
        <label>
          Exercise
          <select value={ex?.id} data-testid="class-exercise" onChange={str(setExercise)}>
            {exercises.value.map((x) => (
              <option key={x.id} value={x.id}>{x.title} ({x.id})</option>
            ))}
          </select>
        </label>
        {ex ? (
          <div class="exercise-info" data-testid="exercise-info">
            <p>{ex.summary}</p>
            <p class="hint">
              {ex.checks.length} checks ({ex.checks.map((c) => c.text).join("; ")}) · {ex.hints.length} hints ·{" "}
              <b>{ex.faults} fault{ex.faults === 1 ? "" : "s"} at start</b> · par time {ex.par_time_s} s · {ex.source}
            </p>
          </div>
        ) : null}
        <label>
          Class id
          <input value={id} required pattern="[a-z0-9][a-z0-9\-]{0,23}" maxLength={24} data-testid="class-id" onInput={str(setId)}
            title="lower-case letters, digits and -, up to 24; the seats' machines are <id>-s01 …" />
        </label>
        <label>
          Title
          <input value={title} maxLength={80} data-testid="class-title" onInput={str(setTitle)} />
        </label>
        <label>
          Seats
          <input type="number" min={1} max={MAX_SEATS} step={1} value={seats} required data-testid="class-seats"
            onInput={(e) => setSeats(Number((e.target as HTMLInputElement).value))} />
          <span class="hint">1 … {MAX_SEATS}</span>
        </label>
        <label class="wide">
          Students (optional, one name a line, seat by seat)
          <textarea rows={4} value={students} data-testid="class-students" onInput={str(setStudents)} />
          {names.length > seats ? <span class="refusal">{names.length} names for {seats} seats</span> : null}
        </label>
        <div class="form-buttons">
          <button type="submit" disabled={busy || !ex} data-testid="class-create">Create class</button>
          <button type="button" class="secondary" onClick={props.onCancel}>Cancel</button>
        </div>
        <RefusalLine refusal={refusal} id="class-create-refusal" />
      </form>
    </Panel>
  );
}

/** The seats' one-time login links, right after the class was made: the service never
 * shows them again (a new link per seat instead). */
export function SeatLinks(props: { created: ClassCreated; onDone: () => void }) {
  const { info } = props.created;
  const [links, setLinks] = useState<SeatLink[]>(props.created.links);
  const [copied, setCopied] = useState<number | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const copy = (l: SeatLink) =>
    void navigator.clipboard.writeText(l.url).then(
      () => setCopied(l.n),
      () => setRefusal({ message: "the browser refused the clipboard: select the link and copy it", problems: [] }),
    );
  const renew = async (n: number) => {
    try {
      const l = await newLink(info.id, n);
      setLinks((ls) => ls.map((x) => (x.n === n ? l : x)));
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
    }
  };
  return (
    <Panel id="seat-links" title={`Login links of class '${info.id}'`}
      actions={<button type="button" data-testid="links-done" onClick={props.onDone}>I have them</button>}>
      <p class="once-note" role="note">
        <b>Shown this once.</b> Each link logs one student into their seat, once, within an hour. Hand them out now;
        a lost link: make a new one for that seat.
      </p>
      <table class="links">
        <tbody>
          {links.map((l) => {
            const seat = info.seats.find((s) => s.n === l.n);
            return (
              <tr key={l.n} data-testid={`seat-link-${l.n}`}>
                <td class="num">{l.n}</td>
                <td>{seat?.student}</td>
                <td><input readOnly value={l.url} class="mono link-url" data-testid="link-url" onFocus={(e) => (e.target as HTMLInputElement).select()} /></td>
                <td>
                  <button type="button" class="secondary" data-testid="link-copy" onClick={() => copy(l)}>{copied === l.n ? "Copied" : "Copy"}</button>{" "}
                  <button type="button" class="link" onClick={() => void renew(l.n)} title="a new link (the old one stays good until used or an hour has passed)">new link</button>
                </td>
              </tr>
            );
          })}
        </tbody>
      </table>
      <RefusalLine refusal={refusal} />
    </Panel>
  );
}
