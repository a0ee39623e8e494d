// Parameter versions (Parameters workspace, "Versions"): take a named version with a note,
// the baseline (the state at the start of commissioning, nudged for until one is set),
// compare any two of versions, live and the manuals' defaults as a table with list and
// engineering units, and roll back to a version (confirmed) → Keep / Revert in the trial bar.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ParamDiff, VersionDiff, VersionInfo } from "../api/types";
import { configureBlocked, may } from "../state/control";
import { paramsVersion, trial } from "../state/params";
import { machineId, online } from "../state/session";
import { baselineOf, compare, deleteVersion, makeBaseline, rollback, takeVersion, versions } from "../state/versions";
import { Panel } from "../ui/Panel";
import { engQty } from "../ui/format";

const when = (t: number) => new Date(t * 1000).toLocaleString([], { dateStyle: "short", timeStyle: "short" });
const text = (v: ParamDiff["before"]) => (v === null || v === undefined ? "—" : String(v));
const why = (e: unknown) => (e instanceof ApiError ? e.refusal.message : e instanceof Error ? e.message : String(e));

/** The states a comparison can name: versions by id, and the three fixed ones. */
function stateOptions(vs: VersionInfo[]) {
  return [
    ...(baselineOf(vs) ? [{ value: "baseline", label: `baseline (${baselineOf(vs)!.name})` }] : []),
    { value: "live", label: "live parameters" },
    { value: "defaults", label: "manuals' defaults" },
    ...vs.map((v) => ({ value: String(v.id), label: `${v.name}${v.baseline ? " ★" : ""} — ${when(v.created_unix)}` })),
  ];
}

/** One end of a comparison: a version, the live lists, the baseline or the defaults. */
function StateSelect(p: { testid: string; value: string; options: { value: string; label: string }[]; onPick: (v: string) => void }) {
  return (
    <select data-testid={p.testid} value={p.value} onChange={(e) => p.onPick((e.target as HTMLSelectElement).value)}>
      {p.options.map((o) => (
        <option key={o.value} value={o.value}>
          {o.label}
        </option>
      ))}
    </select>
  );
}

/** Until the machine has a baseline: a line that says why it matters, and sets one. */
export function BaselineNudge() {
  const vs = versions.value;
  const [message, setMessage] = useState("");
  if (!vs || baselineOf(vs)) return null;
  const allowed = may("versions");
  async function setNow() {
    const stamp = new Date().toISOString().slice(0, 16).replace("T", " ");
    try {
      await takeVersion(`baseline ${stamp}`, "the parameters at the start of commissioning", true);
      setMessage("");
    } catch (e) {
      setMessage(why(e));
    }
  }
  return (
    <span class="baseline-nudge" data-testid="baseline-nudge" role="note">
      No baseline yet: set one before changing parameters, so every change can be compared with
      and rolled back to the state commissioning started from.
      <button type="button" data-testid="baseline-now" disabled={!online.value || !allowed}
        title={allowed ? "" : "your role may not take versions"} onClick={() => void setNow()}>
        Set baseline now
      </button>
      {message ? <span class="inline-error">{message}</span> : null}
    </span>
  );
}

export function DiffTable({ diff }: { diff: ParamDiff[] }) {
  if (!diff.length) return <p class="hint" data-testid="diff-none">No parameter differs.</p>;
  return (
    <div class="table-scroll">
      <table class="params" data-testid="diff-table">
        <thead>
          <tr>
            <th>List</th>
            <th>Parameter</th>
            <th class="num">Before</th>
            <th class="num">After</th>
            <th>Unit</th>
            <th class="num">Engineering</th>
            <th>Takes effect</th>
          </tr>
        </thead>
        <tbody>
          {diff.map((d) => (
            <tr key={`${d.scope}/${d.target}/${d.parameter}`} data-testid={`diff-row-${d.target ?? d.scope}-${d.parameter}`}>
              <td>{d.target ?? d.scope}</td>
              <td>
                <div class="mono">{d.parameter}</div>
                <div class="hint">
                  {d.id} {d.title}
                </div>
              </td>
              <td class="num" data-testid="diff-before">{text(d.before)}</td>
              <td class="num" data-testid="diff-after">{text(d.after)}</td>
              <td>{d.unit}</td>
              <td class="num" data-testid="diff-eng">
                {d.eng_unit && d.eng_unit !== d.unit ? `${engQty(d.before_eng, d.eng_unit)} → ${engQty(d.after_eng, d.eng_unit)}` : ""}
              </td>
              <td>{d.effect}</td>
            </tr>
          ))}
        </tbody>
      </table>
    </div>
  );
}

export function Versions() {
  const vs = versions.value ?? [];
  const [name, setName] = useState("");
  const [note, setNote] = useState("");
  const [message, setMessage] = useState("");
  const [from, setFrom] = useState("baseline");
  const [to, setTo] = useState("live");
  const [diff, setDiff] = useState<VersionDiff | null>(null);
  const [diffError, setDiffError] = useState("");
  const [confirming, setConfirming] = useState<{ v: VersionInfo; diff: ParamDiff[] } | null>(null);
  const allowed = may("versions");
  const notAllowed = allowed ? "" : "your role may not take or change versions";
  const rollbackBlocked = configureBlocked.value || (trial.value ? "Keep or Revert the values on trial first" : "");
  const options = stateOptions(vs);
  const known = (s: string) => options.some((o) => o.value === s);
  const a = known(from) ? from : "defaults"; // no baseline yet: what was changed at all
  const b = known(to) ? to : "live";

  // the comparison follows every parameter write while it involves the live parameters
  const live = a === "live" || b === "live";
  useEffect(() => {
    setDiffError("");
    compare(a, b).then(setDiff, (e) => (setDiff(null), setDiffError(why(e))));
  }, [a, b, machineId.value, vs.length, live ? paramsVersion.value : 0]);

  async function take(baseline: boolean) {
    try {
      const v = await takeVersion(name.trim(), note, baseline);
      setName("");
      setNote("");
      setMessage(`Took ${baseline ? "baseline" : "version"} '${v.name}' (${v.values} written values).`);
    } catch (e) {
      setMessage(why(e));
    }
  }

  async function askRollback(v: VersionInfo) {
    try {
      setConfirming({ v, diff: (await compare("live", String(v.id))).changes });
    } catch (e) {
      setMessage(why(e));
    }
  }

  async function doRollback(v: VersionInfo) {
    try {
      const r = await rollback(v);
      setMessage(r.changes.length ? `Rolled back to '${v.name}': Keep or Revert in the trial bar above.` : "");
    } catch (e) {
      setMessage(why(e));
    }
    setConfirming(null);
  }

  async function act(work: () => Promise<void>) {
    try {
      await work();
      setMessage("");
    } catch (e) {
      setMessage(why(e));
    }
  }

  return (
    <Panel title="Versions" id="versions">
      <BaselineNudge />
      <div class="row version-take">
        <label>
          Name{" "}
          <input data-testid="version-name" size={24} maxLength={80} value={name} placeholder="e.g. after kv tuning X"
            onInput={(e) => setName((e.target as HTMLInputElement).value)} />
        </label>
        <label>
          Note{" "}
          <input data-testid="version-note" size={40} maxLength={1000} value={note} placeholder="what was done, why"
            onInput={(e) => setNote((e.target as HTMLInputElement).value)} />
        </label>
        <button type="button" data-testid="version-take" disabled={!online.value || !name.trim() || !allowed} title={notAllowed}
          onClick={() => void take(false)}>
          Take version
        </button>
        <button type="button" class="secondary" data-testid="version-take-baseline" disabled={!online.value || !name.trim() || !allowed}
          title={notAllowed || "take the live parameters as the machine's baseline"} onClick={() => void take(true)}>
          Take as baseline
        </button>
        {message ? <span class="done-note" data-testid="version-message" role="status">{message}</span> : null}
      </div>
      {confirming ? (
        <div class="param-conflict" data-testid="rollback-confirm" role="alertdialog" aria-label="confirm rollback">
          <p>
            Roll back to <b>{confirming.v.name}</b>? {confirming.diff.length} value(s) will be written as one parameter write
            (values that take effect at reset or restart stay pending). You can Keep or Revert afterwards.
          </p>
          <DiffTable diff={confirming.diff} />
          <button type="button" data-testid="rollback-do" disabled={!online.value || !!rollbackBlocked || !confirming.diff.length}
            title={rollbackBlocked} onClick={() => void doRollback(confirming.v)}>
            Roll back
          </button>
          <button type="button" class="secondary" data-testid="rollback-cancel" onClick={() => setConfirming(null)}>
            Cancel
          </button>
        </div>
      ) : null}
      <table class="params versions" data-testid="version-list">
        <thead>
          <tr>
            <th>Version</th>
            <th>Note</th>
            <th>By</th>
            <th>When</th>
            <th class="num">Values</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {vs.map((v) => (
            <tr key={v.id} data-testid={`version-row-${v.name}`} class={v.baseline ? "baseline" : ""}>
              <td>
                <b>{v.name}</b> {v.baseline ? <span class="tag" data-testid="baseline-tag">baseline</span> : null}
              </td>
              <td>{v.note}</td>
              <td>{v.created_by}</td>
              <td>{when(v.created_unix)}</td>
              <td class="num">{v.values}</td>
              <td class="row version-actions">
                <button type="button" class="secondary" data-testid="version-compare" title="compare this version with the live parameters" onClick={() => (setFrom(String(v.id)), setTo("live"))}>
                  Compare
                </button>
                <button type="button" class="secondary" data-testid="version-rollback" disabled={!online.value || !!rollbackBlocked}
                  title={rollbackBlocked} onClick={() => void askRollback(v)}>
                  Roll back…
                </button>
                {!v.baseline ? (
                  <>
                    <button type="button" class="secondary" data-testid="version-make-baseline" disabled={!online.value || !allowed}
                      title={notAllowed || "make this version the machine's baseline"} onClick={() => void act(() => makeBaseline(v.id))}>
                      Make baseline
                    </button>
                    <button type="button" class="secondary" data-testid="version-delete" disabled={!online.value || !allowed}
                      title={notAllowed} onClick={() => confirm(`Delete version '${v.name}'?`) && void act(() => deleteVersion(v.id))}>
                      Delete
                    </button>
                  </>
                ) : null}
              </td>
            </tr>
          ))}
        </tbody>
      </table>
      {!vs.length ? <p class="hint">No version taken yet.</p> : null}
      <h3>Compare</h3>
      <div class="row">
        <label>
          From{" "}
          <StateSelect testid="diff-from" value={a} options={options} onPick={setFrom} />
        </label>
        <label>
          to{" "}
          <StateSelect testid="diff-to" value={b} options={options} onPick={setTo} />
        </label>
        {diff ? (
          <span class="hint" data-testid="diff-summary">
            {diff.from_label} → {diff.to_label}: {diff.changes.length} difference{diff.changes.length === 1 ? "" : "s"}
          </span>
        ) : null}
        {diffError ? <span class="inline-error">{diffError}</span> : null}
      </div>
      {diff ? <DiffTable diff={diff.changes} /> : null}
    </Panel>
  );
}
