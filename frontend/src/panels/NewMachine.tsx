// A new machine in the Machines dialog: the demo lathe, or native lists uploaded (a channel
// list, one axis list per axis — numbered by its kopf.achs_nr, which the channel's
// log_achs_nr refers to — and a tool list if any). A refused list comes back with its problems
// line by line.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { me } from "../state/auth";
import { may } from "../state/control";
import { createMachine } from "../state/machines";
import { machineId, selectMachine } from "../state/session";
import { RefusalLine } from "../ui/useCommand";

const ID_PATTERN = /^[a-z0-9][a-z0-9_-]{0,31}$/; // as api/machines.py MachineCreate.id

interface AxisFile {
  file: string;
  text: string;
  number: string; // the logical axis number, as typed
}

/** The axis number an axis list gives itself (kopf.achs_nr), "" when it does not. */
const axisNumber = (text: string) => /^\s*kopf\.achs_nr\s+(\d+)/m.exec(text)?.[1] ?? "";

export function NewMachine() {
  const [id, setId] = useState("");
  const [name, setName] = useState("");
  const [demo, setDemo] = useState(true);
  const [channel, setChannel] = useState<{ file: string; text: string } | null>(null);
  const [axes, setAxes] = useState<AxisFile[]>([]);
  const [tools, setTools] = useState<{ file: string; text: string } | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [created, setCreated] = useState("");
  useEffect(() => setCreated(""), [machineId.value]); // old news once another machine is on screen
  if (!may("machines")) {
    return (
      <section class="account-section" aria-label="new machine">
        <h3>New machine</h3>
        <p class="hint">A user in the role {me.value?.role} may not create machines.</p>
      </section>
    );
  }
  const idOk = ID_PATTERN.test(id);
  const numbers = axes.map((a) => Number(a.number));
  const numbersOk = axes.every((a, i) => /^\d+$/.test(a.number) && numbers.indexOf(numbers[i]) === i);
  const listsOk = demo || (!!channel && axes.length > 0 && numbersOk);
  const why = !idOk
    ? "an ID of lower-case letters, digits, - and _ (at most 32), starting with a letter or digit"
    : !listsOk
      ? axes.length && !numbersOk
        ? "every axis list needs its own axis number"
        : "a channel list and at least one axis list"
      : "";

  const read = async (f: File) => ({ file: f.name, text: await f.text() });
  async function create(e: Event) {
    e.preventDefault();
    if (why) return;
    try {
      const m = await createMachine({
        id,
        name,
        demo,
        channel_list: demo ? "" : (channel?.text ?? ""),
        axis_lists: demo ? {} : Object.fromEntries(axes.map((a) => [Number(a.number), a.text])),
        tool_list: demo ? "" : (tools?.text ?? ""),
      });
      setRefusal(null);
      setCreated(m.id);
      setId("");
      setName("");
    } catch (err) {
      setCreated("");
      setRefusal(err instanceof ApiError ? err.refusal : { message: String(err), problems: [] });
    }
  }

  return (
    <section class="account-section" aria-label="new machine" data-testid="new-machine">
      <h3>New machine</h3>
      <form class="account-form" onSubmit={(e) => void create(e)}>
        <label>
          ID <input data-testid="new-machine-id" size={14} value={id} aria-invalid={id !== "" && !idOk}
            onInput={(e) => setId((e.target as HTMLInputElement).value)} />
        </label>
        <label>
          Name <input data-testid="new-machine-name" size={20} value={name} placeholder="(the ID)"
            onInput={(e) => setName((e.target as HTMLInputElement).value)} />
        </label>
        <label>
          <input type="radio" name="new-machine-source" checked={demo} data-testid="new-machine-demo" onChange={() => setDemo(true)} /> demo lathe
        </label>
        <label>
          <input type="radio" name="new-machine-source" checked={!demo} data-testid="new-machine-lists" onChange={() => setDemo(false)} /> from lists
        </label>
        <button type="submit" data-testid="new-machine-create" disabled={!!why} title={why}>
          Create
        </button>
      </form>
      {!demo ? (
        <div class="new-machine-lists">
          <label>
            Channel list{" "}
            <input type="file" accept=".lis,.txt" data-testid="new-machine-channel"
              onChange={(e) => {
                const f = (e.target as HTMLInputElement).files?.[0];
                if (f) void read(f).then(setChannel);
              }} />
          </label>
          <label>
            Axis lists{" "}
            <input type="file" multiple accept=".lis,.txt" data-testid="new-machine-axes"
              onChange={(e) => {
                const files = [...((e.target as HTMLInputElement).files ?? [])];
                void Promise.all(files.map(read)).then((rs) => setAxes(rs.map((r) => ({ ...r, number: axisNumber(r.text) }))));
              }} />
          </label>
          <label>
            Tool list (optional){" "}
            <input type="file" accept=".lis,.txt" data-testid="new-machine-tools"
              onChange={(e) => {
                const f = (e.target as HTMLInputElement).files?.[0];
                if (f) void read(f).then(setTools);
              }} />
          </label>
          {axes.length ? (
            <table class="account-table">
              <thead>
                <tr>
                  <th>Axis list</th>
                  <th>Axis number (log_achs_nr)</th>
                </tr>
              </thead>
              <tbody>
                {axes.map((a, i) => (
                  <tr key={a.file}>
                    <td>{a.file}</td>
                    <td>
                      <input size={4} inputMode="numeric" value={a.number} aria-label={`axis number of ${a.file}`}
                        onInput={(e) => setAxes(axes.map((b, j) => (j === i ? { ...b, number: (e.target as HTMLInputElement).value } : b)))} />
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
          ) : null}
        </div>
      ) : null}
      {why && id !== "" ? <p class="hint">{why}</p> : null}
      {created ? (
        <p data-testid="new-machine-created">
          Machine <b>{created}</b> created and running.{" "}
          <button type="button" class="secondary" onClick={() => selectMachine(created)}>Open it</button>
        </p>
      ) : null}
      <RefusalLine refusal={refusal} id="new-machine-refusal" />
      {refusal?.problems?.length ? (
        <ul class="list-problems" data-testid="new-machine-problems">
          {refusal.problems.map((p, i) => (
            <li key={i}>
              {p.line != null ? `line ${p.line}: ` : ""}
              {p.parameter ? <b>{p.parameter}</b> : null} {p.message}
            </li>
          ))}
        </ul>
      ) : null}
    </section>
  );
}
