// The parameter editor: lists grouped by topic and gear record, search, raw and engineering
// units, ranges, pending values; edit → Apply (on the running machine) → Keep or Revert;
// import and export of the native list file. The trial bar (Keep/Revert) is TrialBar.
import { useEffect, useMemo, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { ParameterProblem, ParameterValue, ParameterWriteResult, Scope, StaleValue } from "../api/types";
import { configureBlocked } from "../state/control";
import {
  type Change,
  dtypes,
  listUrl,
  loadList,
  loadRegistry,
  paramListView,
  registryDefs,
  paramsVersion,
  trial,
  trialMessage,
  writeChanges,
} from "../state/params";
import { axisOutline, machineId, online } from "../state/session";
import { Panel } from "../ui/Panel";
import { engQty, multiGainText } from "../ui/format";
import { paramView } from "../state/versions";
import { groupOf } from "./paramGroups";
import { BaselineNudge, Versions } from "./Versions";

interface Target {
  scope: Scope;
  target: string | null;
  label: string;
}

const num = (v: number) => (Math.abs(v) >= 1e15 ? v.toExponential(3) : String(+v.toPrecision(12)));

const INTEGER_TYPES = new Set(["UNS16", "UNS32", "SGN16", "SGN32", "BOOLEAN"]);
/** Symbols and text the service parses itself (enums, flags, strings). */
const TEXT_TYPES = new Set(["STRING", "ENUM", "FLAGS"]);

/** Inline check of an edited value against the entry's registry type and range; null when
 * fine. `dtype` is the registry's data type (UNS32, REAL64, …). */
export function checkValue(p: ParameterValue, text: string, dtype: string | undefined): string | null {
  if (typeof p.default === "string" || (dtype && TEXT_TYPES.has(dtype))) return null;
  const v = Number(text.trim());
  if (text.trim() === "" || !Number.isFinite(v)) return "a number is needed";
  if (dtype && INTEGER_TYPES.has(dtype) && !Number.isInteger(v)) return `${dtype} takes whole numbers`;
  const unit = p.unit ? ` ${p.unit}` : "";
  if ((p.min != null && v < p.min) || (p.max != null && v > p.max))
    return `out of range ${num(p.min ?? -Infinity)} … ${num(p.max ?? Infinity)}${unit}`;
  return null;
}

/** A write refused because someone else wrote a value since it was read: what was sent, and
 * the values in force now. */
interface Conflict {
  changes: Change[];
  stale: StaleValue[];
}

const clock = (t: number | null) =>
  t == null ? "" : ` at ${new Date(t * 1000).toLocaleTimeString([], { hour: "2-digit", minute: "2-digit" })}`;

/** "NAME changed getriebe[0].kv to 1.5 at 10:31 — yours: 2.0" */
const staleLine = (s: StaleValue) =>
  `${s.by} changed ${s.parameter} to ${s.current === null ? "its default" : String(s.current)}${clock(s.time_unix)} — yours: ${String(s.yours)}`;

/** "line 3: getriebe[0].kv: …" for an import's problems (the API gives the line). */
const problemLine = (p: ParameterProblem) => `${p.line != null ? `line ${p.line}: ` : ""}${p.message}`;

/** The workspace: the list editor, or the parameter versions (with a nudge to set the
 * baseline until there is one). */
export function Parameters() {
  const view = paramView.value;
  return (
    <>
      {/* two toggle buttons (aria-pressed), not tabs: the nudge beside them is no tab */}
      <div class="row subviews" role="group" aria-label="parameter views">
        {(["list", "versions"] as const).map((v) => (
          <button key={v} type="button" class="secondary" aria-pressed={view === v}
            data-testid={`param-view-${v}`} onClick={() => (paramView.value = v)}>
            {v === "list" ? "Lists" : "Versions"}
          </button>
        ))}
        {view === "list" ? <BaselineNudge /> : null}
      </div>
      {view === "list" ? <ParameterList /> : <Versions />}
    </>
  );
}

function ParameterList() {
  const axes = axisOutline.value;
  const targets: Target[] = [
    ...axes.map((a) => ({ scope: "axis" as const, target: a.name, label: `Axis ${a.name}` })),
    { scope: "channel", target: null, label: "Channel" },
    { scope: "tool", target: null, label: "Tools" },
  ];
  const { list: which, query, group } = paramListView.value;
  const t = targets.find((x) => x.label === which) ?? targets[0];
  const spindle = axes.find((a) => a.name === t?.target)?.kind === "spindle";
  const [rows, setRows] = useState<ParameterValue[]>([]);
  const [edits, setEdits] = useState<Record<string, string>>({});
  const [problems, setProblems] = useState<ParameterProblem[]>([]);
  const [message, setMessage] = useState("");
  const [conflict, setConflict] = useState<Conflict | null>(null);
  const blocked = configureBlocked.value; // another holder, or a role that may not configure
  const types = dtypes.value;
  useEffect(() => void loadRegistry(), []);
  const check = (p: ParameterValue, text: string) => checkValue(p, text, types.get(p.id));

  const reload = () => t && machineId.value && loadList(t.scope, t.target).then(setRows, () => undefined);
  useEffect(() => {
    setEdits({});
    setProblems([]);
    setConflict(null);
    // only the list still open takes its answer: a slow answer for the list open before
    // (the axis list at mount, then Channel chosen) must not replace the one chosen since
    let open = true;
    if (t && machineId.value) loadList(t.scope, t.target).then((r) => open && setRows(r), () => undefined);
    return () => {
      open = false;
    };
  }, [t?.label, machineId.value, paramsVersion.value]);

  const groups = useMemo(() => [...new Set(rows.map((p) => groupOf(p.name, p.gear, spindle)))], [rows, spindle]);
  const q = query.trim().toLowerCase();
  const shownFlat = rows.filter(
    (p) =>
      (!group || groupOf(p.name, p.gear, spindle) === group) &&
      (!q || p.id.toLowerCase().includes(q) || p.name.toLowerCase().includes(q) || p.title.toLowerCase().includes(q)),
  );
  // grouped: every group's rows together, groups in the order they first appear
  const shownGroups = groups
    .map((g) => ({ g, rows: shownFlat.filter((p) => groupOf(p.name, p.gear, spindle) === g) }))
    .filter((x) => x.rows.length);
  // a search the open list cannot answer: the registry says in which scope it is (an axis
  // parameter may belong to another kind of axis, e.g. a spindle's, so every other axis is offered)
  const elsewhere = !shownFlat.length && q
    ? registryDefs.value.filter((d) => d.id.toLowerCase().includes(q) || d.name.toLowerCase().includes(q) || d.title.toLowerCase().includes(q))
    : [];
  const scopes = new Set(elsewhere.map((d) => d.scope));
  const otherLists = targets.filter((x) => x.label !== t?.label && scopes.has(x.scope));
  const byName = new Map(rows.map((p) => [p.name, p]));
  const invalid = Object.entries(edits).filter(([n, v]) => byName.has(n) && check(byName.get(n)!, v));
  const edited = Object.keys(edits).length;

  async function write(changes: Change[], comment: string) {
    if (!t) return null;
    try {
      const r = await writeChanges(t.scope, t.target, changes, comment);
      setProblems([]);
      setConflict(null);
      return r;
    } catch (e) {
      if (e instanceof ApiError) {
        setProblems(e.refusal.problems ?? []);
        setMessage(e.refusal.message);
        const stale = e.refusal.stale ?? [];
        setConflict(e.status === 409 && stale.length ? { changes, stale } : null);
      }
      return null;
    }
  }

  async function apply() {
    const changes = Object.entries(edits).map(([name, text]) => {
      const p = byName.get(name)!;
      // the version read with the value: a write over someone else's newer value is refused
      return { name, value: typeof p.default === "string" ? text : Number(text), base_version: p.version };
    });
    await applyChanges(changes);
  }

  /** The same values again, now based on the versions in force: the user saw both and chose. */
  async function writeMineAnyway(c: Conflict) {
    const now = new Map(c.stale.map((s) => [s.parameter, s.version]));
    await applyChanges(c.changes.map((ch) => ({ ...ch, base_version: now.get(ch.name) ?? ch.base_version })));
  }

  /** Drop the edits someone else overtook and show their values. */
  function keepTheirs(c: Conflict) {
    const overtaken = new Set(c.stale.map((s) => s.parameter));
    setEdits(Object.fromEntries(Object.entries(edits).filter(([n]) => !overtaken.has(n))));
    setConflict(null);
    setMessage("");
    void reload();
  }

  async function applyChanges(changes: Change[]) {
    const r = await write(changes, "editor: apply (trial)");
    if (r && t) {
      setEdits({});
      // only values that differ are changes: nothing to keep or revert when none did
      trial.value = r.changes.length ? { machine: machineId.value, scope: t.scope, target: t.target, applied: r.changes } : null;
      trialMessage.value = "";
      setMessage(r.changes.length ? "" : "No value changed: every value was already set.");
    }
  }

  async function importFile(file: File) {
    if (!t) return;
    try {
      const r = await http.postText<ParameterWriteResult>(listUrl("/import", t.scope, t.target), await file.text());
      setProblems([]);
      const n = r.changes.length; // the service reports only values that differ
      setMessage(`Imported ${file.name}: ${n ? `${n} value${n === 1 ? "" : "s"} changed.` : "no value changed (the list matches the machine)."}`);
      paramsVersion.value++;
    } catch (e) {
      if (e instanceof ApiError) {
        const problems = e.refusal.problems ?? [];
        setProblems(problems);
        // every rejected line with its number: the rows below show only this list's entries
        setMessage(`${file.name}: ${problems.length ? problems.map(problemLine).join("; ") : e.refusal.message}`);
      }
    }
  }

  /** multi_gain_z and _n read as their ratio (the gear record's other half as it stands or
   * is being edited) [004 §3.6.2]. */
  const multiGain = (p: ParameterValue, v: ParameterValue["value"]): string | null => {
    const m = /^(getriebe\[\d+\]\.multi_gain_)([zn])$/.exec(p.name);
    if (!m || typeof v !== "number") return null;
    const other = byName.get(`${m[1]}${m[2] === "z" ? "n" : "z"}`);
    const edited = other ? edits[other.name] : undefined;
    const ov = edited !== undefined && other && !check(other, edited) ? Number(edited) : other?.value;
    if (typeof ov !== "number") return null;
    const [z, n] = m[2] === "z" ? [v, ov] : [ov, v];
    return multiGainText(z, n, axes.find((a) => a.name === t?.target)?.kind === "linear");
  };
  const problemOf = (name: string) => problems.find((p) => p.parameter === name);
  // the gear record the axis uses now (getriebe[gear − 1]; an axis without gears: [0])
  const gearNow = axes.find((a) => a.name === t?.target)?.gear ?? 1;
  const activeRecord = (name: string): boolean => {
    const m = /^getriebe\[(\d+)\]\./.exec(name);
    return !!m && Number(m[1]) === gearNow - 1;
  };
  return (
    <Panel title="Parameters" id="parameters">
      <div class="row param-tools">
        <label>
          List{" "}
          <select data-testid="param-target" value={t?.label} onChange={(e) => paramListView.patch({ list: (e.target as HTMLSelectElement).value, group: "" })}>
            {targets.map((x) => (
              <option key={x.label}>{x.label}</option>
            ))}
          </select>
        </label>
        <label>
          Group{" "}
          <select data-testid="param-group" value={group} onChange={(e) => paramListView.patch({ group: (e.target as HTMLSelectElement).value })}>
            <option value="">all</option>
            {groups.map((g) => (
              <option key={g}>{g}</option>
            ))}
          </select>
        </label>
        <input type="search" data-testid="param-search" size={32} placeholder="Search ID, name or description" value={query}
          onInput={(e) => paramListView.patch({ query: (e.target as HTMLInputElement).value })} aria-label="search parameters" />
        <a class="button secondary" href={t && machineId.value ? listUrl("/export", t.scope, t.target) : "#"}
          download={`${machineId.value}-${t?.target ?? t?.scope}.lis`}>
          Export list
        </a>
        <label class={`button secondary ${blocked ? "disabled" : ""}`} title={blocked} data-testid="param-import">
          Import list…
          <input type="file" accept=".lis,.txt,text/plain" hidden disabled={!!blocked}
            onChange={(e) => {
              const f = (e.target as HTMLInputElement).files?.[0];
              if (f) void importFile(f);
              (e.target as HTMLInputElement).value = "";
            }} />
        </label>
      </div>
      <div class="row apply-bar">
        {/* one trial at a time: a second Apply would take the first one's Revert away */}
        <button type="button" data-testid="param-apply" disabled={!online.value || !edited || invalid.length > 0 || !!trial.value || !!blocked}
          title={blocked || (trial.value ? "Keep or Revert the values on trial first" : "")} onClick={() => void apply()}>
          Apply {edited ? `(${edited})` : ""}
        </button>
        <button type="button" class="secondary" disabled={!edited} onClick={() => (setEdits({}), setProblems([]))}>
          Discard edits
        </button>
        {message ? <span class="hint" data-testid="param-message">{message}</span> : null}
      </div>
      {conflict ? (
        <div class="param-conflict" data-testid="param-conflict" role="alert">
          <ul>
            {conflict.stale.map((s) => (
              <li key={s.parameter} data-testid={`param-stale-${s.parameter}`}>
                {staleLine(s)}
              </li>
            ))}
          </ul>
          <button type="button" data-testid="param-write-anyway" disabled={!online.value || !!blocked} title={blocked}
            onClick={() => void writeMineAnyway(conflict)}>
            Write mine anyway
          </button>
          <button type="button" class="secondary" data-testid="param-keep-theirs" onClick={() => keepTheirs(conflict)}>
            Keep theirs
          </button>
        </div>
      ) : null}
      <div class="table-scroll">
        <table class="params">
          <thead>
            <tr>
              <th>ID</th>
              <th>Name / description</th>
              <th class="num">Value</th>
              <th>Unit</th>
              <th class="num">Engineering</th>
              <th>Range</th>
              <th class="num">Default</th>
              <th>Takes effect</th>
            </tr>
          </thead>
          {shownGroups.map(({ g, rows: groupRows }) => (
          <tbody key={g}>
            <tr class="group-row">
              <th colSpan={8}>{g}</th>
            </tr>
            {groupRows.map((p) => {
              const text = edits[p.name];
              const err = text !== undefined ? check(p, text) : null;
              const server = problemOf(p.name);
              const v = text !== undefined && !err && typeof p.value === "number" ? Number(text) : p.value;
              return (
                <tr key={p.name} data-testid={`param-row-${p.name}`} class={text !== undefined ? "edited" : ""}>
                  <td class="mono">{p.id}</td>
                  <td>
                    <div class="mono">
                      {p.name}
                      {activeRecord(p.name) ? (
                        <span class="tag in-force-tag" data-testid={`param-active-${p.name}`} title="the gear record in force now">
                          in force
                        </span>
                      ) : null}
                    </div>
                    <div class="hint">{p.title}</div>
                    {p.without_effect ? (
                      <div class="hint no-effect" data-testid={`param-no-effect-${p.name}`}>
                        <span class="tag no-effect-tag">no effect here</span> {p.without_effect}
                      </div>
                    ) : null}
                  </td>
                  <td class="num">
                    <input
                      class="param-input"
                      data-testid={`param-input-${p.name}`}
                      aria-label={`${p.name} value`}
                      aria-invalid={!!err || !!server}
                      value={text ?? String(p.value)}
                      size={10}
                      onInput={(e) => setEdits({ ...edits, [p.name]: (e.target as HTMLInputElement).value })}
                    />
                    {err || server ? (
                      <div class="inline-error" data-testid={`param-error-${p.name}`} role="alert">
                        {err ?? (server ? problemLine(server) : null)}
                      </div>
                    ) : null}
                  </td>
                  <td>{p.unit}</td>
                  <td class="num" data-testid={`param-eng-${p.name}`}>
                    {multiGain(p, v) ?? (typeof v === "number" && p.eng_factor != null && (p.eng_unit !== p.unit || p.eng_factor !== 1)
                      ? engQty(v * p.eng_factor, p.eng_unit)
                      : "")}
                  </td>
                  <td class="hint">{p.min != null ? `${num(p.min)} … ${num(p.max ?? Infinity)}` : ""}</td>
                  <td class="num">{String(p.default)}</td>
                  <td>
                    {p.effect}
                    {p.pending !== null && p.pending !== undefined ? (
                      <span class="pending" data-testid={`param-pending-${p.name}`}>
                        pending {String(p.pending)} at {p.effect}
                      </span>
                    ) : null}
                    {!p.set ? <span class="hint"> (default)</span> : null}
                  </td>
                </tr>
              );
            })}
          </tbody>
          ))}
        </table>
        {!shownFlat.length ? (
          <p class="hint" data-testid="param-no-match">
            No parameter matches in this list.
            {elsewhere.length ? (
              <>
                {" "}Found in the registry for {elsewhere.map((d) => d.id).slice(0, 3).join(", ")}
                {elsewhere.length > 3 ? ` and ${elsewhere.length - 3} more` : ""}: look in{" "}
                {otherLists.map((x) => (
                  <button key={x.label} type="button" class="link" data-testid={`param-look-${x.label}`}
                    onClick={() => paramListView.patch({ list: x.label, group: "" })}>
                    {x.label}
                  </button>
                ))}
              </>
            ) : null}
          </p>
        ) : null}
      </div>
    </Panel>
  );
}
