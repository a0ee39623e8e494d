// A new class: its lesson plan, one exercise or several in order (what each asks, its checks
// and hints, how many faults it injects, what varies per seat, which assistants it locks),
// the seats' machine (the demo lathe or uploaded parameter lists: a channel list, one axis list
// per axis with its logical axis number, optionally a tool list), how many seats, the
// students' names; then each seat's one-time login link, shown this once.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ClassCreated, ExerciseInfo, MachineLists, Refusal, SeatLink } from "../api/types";
import { chooseClass, createClass, exercises, newLink } from "../state/classes";
import { loadRoster, roster } from "../state/roster";
import { LinkSheet } from "./LinkSheet";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";

const MAX_SEATS = 60; // api/classes.py MAX_SEATS
const MAX_PLAN = 8; // api/classes.py MAX_PLAN
const LOOPBACK = /^(127\.|localhost$|\[::1\]$)/;

/** What an exercise of the plan brings, in a line. */
function ExerciseLine(props: { ex: ExerciseInfo; k: number; plan: number }) {
  const { ex } = props;
  return (
    <div class="exercise-info" data-testid={`exercise-info-${props.k}`}>
      <p>{props.plan > 1 ? <b>{props.k + 1}. {ex.title}: </b> : null}{ex.summary}</p>
      <p class="hint">
        {ex.checks.length} check{ex.checks.length === 1 ? "" : "s"} ({ex.checks.map((c) => c.text).join("; ")}) · {ex.hints.length} hints ·{" "}
        <b>{ex.faults} fault{ex.faults === 1 ? "" : "s"} at start</b> · par time {ex.par_time_s} s · {ex.source}
        {ex.varied.length ? <> · <b>each seat its own numbers</b> ({ex.varied.join(", ")})</> : null}
        {ex.locked_assistants.length ? <> · locks the assistants {ex.locked_assistants.join(", ")}</> : null}
      </p>
    </div>
  );
}

/** An uploaded axis list and its logical axis number (log_achs_nr), which the channel list's
 * achse[i].log_achs_nr / spindel[i].log_achs_nr refer to. */
interface AxisFile {
  name: string;
  text: string;
  nr: string;
}

/** The axis number an axis list gives itself (kopf.achs_nr), else the digits of its file
 * name (axis_3.lis), else "". */
function axisNumber(name: string, text: string): string {
  const own = /^\s*kopf\.achs_nr\s+(\d+)/m.exec(text);
  return own?.[1] ?? /(\d+)\D*$/.exec(name)?.[1] ?? "";
}

const readFiles = (input: HTMLInputElement) =>
  Promise.all(Array.from(input.files ?? []).map(async (f) => ({ name: f.name, text: await f.text() })));

/** The seats' machine: the demo lathe, or parameter lists from files. */
function TemplateChoice(props: {
  upload: boolean;
  setUpload: (u: boolean) => void;
  channel: { name: string; text: string } | null;
  setChannel: (c: { name: string; text: string } | null) => void;
  axes: AxisFile[];
  setAxes: (a: AxisFile[]) => void;
  tools: { name: string; text: string } | null;
  setTools: (t: { name: string; text: string } | null) => void;
}) {
  const { upload, axes } = props;
  const one = (set: (f: { name: string; text: string } | null) => void) => (e: Event) =>
    void readFiles(e.target as HTMLInputElement).then((fs) => set(fs[0] ?? null));
  return (
    <fieldset class="wide template" data-testid="class-template">
      <legend>Machine of every seat</legend>
      <label class="inline">
        <input type="radio" name="template" checked={!upload} data-testid="template-demo" onChange={() => props.setUpload(false)} /> Demo lathe
      </label>
      <label class="inline">
        <input type="radio" name="template" checked={upload} data-testid="template-lists" onChange={() => props.setUpload(true)} /> Upload
        parameter lists
      </label>
      {upload ? (
        <div class="template-files">
          <label>
            Channel list (.lis)
            <input type="file" accept=".lis,.txt,text/plain" required data-testid="lists-channel" onChange={one(props.setChannel)} />
          </label>
          <label>
            Axis lists (.lis, one per axis and spindle)
            <input type="file" accept=".lis,.txt,text/plain" multiple required data-testid="lists-axes"
              onChange={(e) =>
                void readFiles(e.target as HTMLInputElement).then((fs) =>
                  props.setAxes(fs.map((f) => ({ ...f, nr: axisNumber(f.name, f.text) }))),
                )
              } />
          </label>
          <label>
            Tool list (.lis, optional)
            <input type="file" accept=".lis,.txt,text/plain" data-testid="lists-tools" onChange={one(props.setTools)} />
          </label>
          {axes.length ? (
            <table class="axis-files" data-testid="lists-axis-numbers">
              <thead>
                <tr><th>axis list</th><th>logical axis number (log_achs_nr)</th></tr>
              </thead>
              <tbody>
                {axes.map((a, i) => (
                  <tr key={a.name}>
                    <td class="mono">{a.name}</td>
                    <td>
                      <input type="number" min={1} max={255} step={1} required value={a.nr} aria-label={`logical axis number of ${a.name}`}
                        data-testid={`lists-axis-nr-${i}`}
                        onInput={(e) => props.setAxes(axes.map((x, j) => (j === i ? { ...x, nr: (e.target as HTMLInputElement).value } : x)))} />
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
          ) : null}
          <p class="hint">
            The channel list names each axis and spindle with its logical axis number; each axis list is taken for the
            number beside it (read from its kopf.achs_nr, else from the file name). The exercise's axes, spindles and
            gear stages must be in the lists.
          </p>
        </div>
      ) : null}
    </fieldset>
  );
}

/** The lists as ClassCreate.lists; a sentence for what is missing. */
function listsOf(
  channel: { text: string } | null,
  axes: AxisFile[],
  tools: { text: string } | null,
): MachineLists | string {
  if (!channel) return "choose the channel list";
  if (!axes.length) return "choose the axis lists";
  const byNr: Record<string, string> = {};
  for (const a of axes) {
    if (!/^\d+$/.test(a.nr)) return `give ${a.name} its logical axis number`;
    if (a.nr in byNr) return `two axis lists have number ${a.nr}`;
    byNr[a.nr] = a.text;
  }
  return { channel_list: channel.text, axis_lists: byNr, tool_list: tools?.text ?? "" };
}

export function CreateClass(props: { onCreated: (c: ClassCreated) => void; onCancel: () => void }) {
  // a class id to start from: the day (an instructor's own is welcome)
  const [id, setId] = useState(() => `class-${new Date().toISOString().slice(5, 10).replace("-", "")}`);
  const [title, setTitle] = useState("");
  const [picked, setPlan] = useState<string[]>([]);
  // the first exercise until one is picked (the list may come after the form)
  const plan = picked.length ? picked : exercises.value[0] ? [exercises.value[0].id] : [];
  const [seats, setSeats] = useState(2);
  const [students, setStudents] = useState("");
  const [upload, setUpload] = useState(false);
  const [channel, setChannel] = useState<{ name: string; text: string } | null>(null);
  const [axes, setAxes] = useState<AxisFile[]>([]);
  const [tools, setTools] = useState<{ name: string; text: string } | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const [linkHours, setLinkHours] = useState(1); // prepared the day before: 24 h
  const [keep, setKeep] = useState(false); // the students are people of the roster
  useEffect(() => void loadRoster().catch(() => undefined), []);
  const byId = (eid: string) => exercises.value.find((e) => e.id === eid);
  const chosen = plan.map(byId).filter((e): e is ExerciseInfo => e !== undefined);
  const setAt = (k: number, eid: string) => setPlan(plan.map((x, j) => (j === k ? eid : x)));
  const unused = exercises.value.filter((e) => !plan.includes(e.id));
  const names = students.split("\n").map((s) => s.trim()).filter(Boolean);
  async function submit(e: Event) {
    e.preventDefault();
    const lists = upload ? listsOf(channel, axes, tools) : null;
    if (typeof lists === "string") {
      setRefusal({ message: lists, problems: [] });
      return;
    }
    setBusy(true);
    try {
      const created = await createClass({ id, title, exercises: plan, seats, students: names, lists, link_hours: linkHours, roster: keep });
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
        <fieldset class="wide plan" data-testid="class-plan">
          <legend>Lesson plan: the exercises in order</legend>
          {plan.map((eid, k) => (
            <div class="plan-row" key={k}>
              <label>
                {k === 0 ? (plan.length > 1 ? "1. Exercise" : "Exercise") : `${k + 1}. then`}
                <select value={eid} data-testid={k === 0 ? "class-exercise" : `class-plan-${k}`} onChange={(e) => setAt(k, (e.target as HTMLSelectElement).value)}>
                  {exercises.value.filter((x) => x.id === eid || !plan.includes(x.id)).map((x) => (
                    <option key={x.id} value={x.id}>{x.title} ({x.id})</option>
                  ))}
                </select>
              </label>
              {k > 0 ? (
                <button type="button" class="link" data-testid={`class-plan-remove-${k}`} onClick={() => setPlan(plan.filter((_, j) => j !== k))}>remove</button>
              ) : null}
            </div>
          ))}
          {plan.length < MAX_PLAN && unused.length ? (
            <button type="button" class="secondary" data-testid="class-plan-add" onClick={() => setPlan([...plan, unused[0].id])}>
              + Then another exercise
            </button>
          ) : null}
          {chosen.map((x, k) => <ExerciseLine key={x.id} ex={x} k={k} plan={chosen.length} />)}
          {chosen.length > 1 ? (
            <p class="hint">
              Each exercise has its own clock and score. A student moves on once every check has passed; you can move seats on at
              any time (console: Next exercise).
            </p>
          ) : null}
        </fieldset>
        <TemplateChoice upload={upload} setUpload={setUpload} channel={channel} setChannel={setChannel} axes={axes} setAxes={setAxes}
          tools={tools} setTools={setTools} />
        <label>
          Class id
          <input value={id} required pattern="[a-z0-9][a-z0-9\-]{0,23}" maxLength={24} data-testid="class-id" onInput={str(setId)}
            title="lower-case letters, digits and -, up to 24; the seats' machines are <id>-s01 …" />
          <span class="hint">a-z, 0-9 and -; the seats are {id || "<id>"}-s01 …</span>
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
        <label>
          Login links good for
          <select value={linkHours} data-testid="class-link-hours" onChange={(e) => setLinkHours(Number((e.target as HTMLSelectElement).value))}>
            <option value={1}>1 hour</option>
            <option value={8}>8 hours</option>
            <option value={24}>24 hours (links made the day before)</option>
            <option value={72}>3 days</option>
          </select>
        </label>
        <label class="wide">
          Students (optional, one name a line, seat by seat)
          <textarea rows={4} value={students} data-testid="class-students" onInput={str(setStudents)} />
          {names.length > seats ? <span class="refusal">{names.length} names for {seats} seats</span> : null}
        </label>
        <div class="wide roster-pick">
          <label class="inline">
            <input type="checkbox" checked={keep} data-testid="class-roster" onChange={(e) => setKeep((e.target as HTMLInputElement).checked)} />{" "}
            Keep them on the roster (each name one student across classes, with their results; logins stay per seat)
          </label>
          {roster.value.length ? (
            <select value="" aria-label="add a student of the roster" data-testid="class-roster-add"
              onChange={(e) => {
                const name = (e.target as HTMLSelectElement).value;
                if (name) { setStudents([...names, name].join("\n")); setKeep(true); }
              }}>
              <option value="">Add from the roster…</option>
              {roster.value.filter((s) => !names.includes(s.name)).map((s) => (
                <option key={s.id} value={s.name}>{s.name}</option>
              ))}
            </select>
          ) : null}
        </div>
        <div class="form-buttons">
          <button type="submit" disabled={busy || !chosen.length} data-testid="class-create">Create class</button>
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
  const clip = (text: string, n: number) =>
    void navigator.clipboard.writeText(text).then(
      () => setCopied(n),
      () => setRefusal({ message: "the browser refused the clipboard: select the link and copy it", problems: [] }),
    );
  const copy = (l: SeatLink) => clip(l.url, l.n);
  // every seat a line: seat, student, link (tab-separated: pastes into a spreadsheet)
  const copyAll = () =>
    clip(links.map((l) => `${l.n}\t${info.seats.find((s) => s.n === l.n)?.student ?? ""}\t${l.url}`).join("\n"), 0);
  const until = links.length ? new Date(Math.min(...links.map((l) => l.expires_unix)) * 1000).toLocaleString() : "";
  const renew = async (n: number) => {
    try {
      const l = await newLink(info.id, n);
      setLinks((ls) => ls.map((x) => (x.n === n ? l : x)));
    } catch (e) {
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });
    }
  };
  return (
    <Panel id="seat-links" title={`Login links of class ${info.title || info.id} (${info.id})`}
      actions={
        <span class="link-actions">
          <button type="button" class="secondary" data-testid="links-copy-all" onClick={copyAll}>{copied === 0 ? "Copied all" : "Copy all"}</button>{" "}
          <button type="button" class="secondary" data-testid="links-print" onClick={() => window.print()}>Print the sheet (QR codes)</button>{" "}
          <button type="button" data-testid="links-done" onClick={props.onDone}>I have them</button>
        </span>
      }>
      {links.some((l) => LOOPBACK.test(new URL(l.url).hostname)) ? (
        <p class="refusal" role="alert" data-testid="links-loopback">
          These links point to {new URL(links[0].url).host}: only this computer can open them. For students on other PCs or
          phones, open the console by the service's network name (the service listening there, e.g. behind the reverse proxy
          with --behind-proxy) and make the links again.
        </p>
      ) : null}
      <p class="once-note" role="note">
        <b>Shown this once.</b> Each link logs one student into their seat, once, until {until}. Hand them out, print the sheet
        or copy them all; a lost link: make a new one for that seat (it logs out whoever used the old one).
      </p>
      <LinkSheet info={info} links={links} />
      <table class="links">
        <tbody>
          {links.map((l) => {
            const seat = info.seats.find((s) => s.n === l.n);
            return (
              <tr key={l.n} data-testid={`seat-link-${l.n}`}>
                <td class="num">{l.n}</td>
                <td>{seat?.student}</td>
                <td><input readOnly value={l.url} aria-label={`login link of seat ${l.n}`} class="mono link-url" data-testid="link-url" onFocus={(e) => (e.target as HTMLInputElement).select()} /></td>
                <td>
                  <button type="button" class="secondary" data-testid="link-copy" onClick={() => copy(l)}>{copied === l.n ? "Copied" : "Copy"}</button>{" "}
                  <button type="button" class="link" onClick={() => void renew(l.n)} title="a new link: the seat's old link and any session logged in with it end">new link</button>
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
