// The machine's history: one timeline of job errors (with the command that raised them),
// events, commands and their outcomes, parameter and control changes, power-ons, service
// starts and stops and notes, with wall clock, machine time and who; kept across restarts.
// Filtered, older pages on demand, new entries live, exported as CSV or JSON, and a logbook
// entry written from here. A job error links to the flight recorder's trace of the seconds
// around it (in the scope, in Rerun); the recorder saves the last seconds on demand too.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { FlightRecorderStatus, HistoryEntry, HistoryKind, HistoryPage, TraceInfo } from "../api/types";
import { me } from "../state/auth";
import { may } from "../state/control";
import { liveHistory } from "../state/history";
import { openTrace } from "../state/route";
import { machineId } from "../state/session";
import { TIME_RANGES, TYPING_MS, wallTime } from "../ui/logFilters";
import { Panel } from "../ui/Panel";
import { fmt } from "../ui/format";

const PAGE = 100;
/** What to look at: groups of kinds (none: everything). */
const GROUPS: { label: string; kinds: HistoryKind[] }[] = [
  { label: "everything", kinds: [] },
  { label: "alarms", kinds: ["job_error", "cleared", "acknowledged"] },
  { label: "commands", kinds: ["command"] },
  { label: "parameters and versions", kinds: ["parameter", "version", "assist"] },
  { label: "control", kinds: ["control"] },
  { label: "power-ons and service", kinds: ["power", "service", "machine", "simulation"] },
  { label: "notes", kinds: ["note"] },
  { label: "NC events", kinds: ["event"] },
  { label: "traces, programs, reports", kinds: ["trace", "recording", "program", "report", "training"] },
];
const SEVERITIES: { label: string; values: HistoryEntry["severity"][] }[] = [
  { label: "any", values: [] },
  { label: "warnings and errors", values: ["warning", "error"] },
  { label: "errors", values: ["error"] },
];
const KIND_WORDS: Partial<Record<HistoryKind, string>> = {
  job_error: "✖ job error",
  cleared: "✓ cleared",
  acknowledged: "☑ acknowledged",
  event: "ℹ event",
  power: "↻ power-on",
  service: "⚙ service",
  note: "✎ note",
};

interface Filter {
  group: number;
  severity: number;
  back_s: number;
  actor: string;
  text: string;
}

function query(f: Filter): URLSearchParams {
  const q = new URLSearchParams();
  GROUPS[f.group].kinds.forEach((k) => q.append("kind", k));
  SEVERITIES[f.severity].values.forEach((s) => q.append("severity", s));
  if (f.actor.trim()) q.set("actor", f.actor.trim());
  if (f.text.trim()) q.set("text", f.text.trim());
  if (f.back_s) q.set("since_unix", String(Math.floor(Date.now() / 1000 - f.back_s)));
  return q;
}

/** Whether a live entry belongs in the filtered view (as the service would filter it). */
function matches(e: HistoryEntry, f: Filter): boolean {
  const kinds = GROUPS[f.group].kinds;
  const severities = SEVERITIES[f.severity].values;
  const text = f.text.trim().toLowerCase();
  return (
    (!kinds.length || kinds.includes(e.kind)) &&
    (!severities.length || severities.includes(e.severity)) &&
    (!f.actor.trim() || e.actor.toLowerCase().includes(f.actor.trim().toLowerCase())) &&
    (!f.back_s || e.time_unix >= Date.now() / 1000 - f.back_s) &&
    (!text || `${e.text} ${e.outcome} ${e.cause ?? ""}`.toLowerCase().includes(text))
  );
}

const newestFirst = (a: HistoryEntry, b: HistoryEntry) => b.time_unix - a.time_unix;


const machineBase = () => `/api/machines/${encodeURIComponent(machineId.value)}/history`;

/** A stretch of time as the recorder's hint says it: seconds, minutes from two. */
const span = (s: number) => (s < 120 ? `${fmt(s, 0)} s` : `${fmt(s / 60, 1)} min`);

/** The machine's history, or (`bundle`) an opened bundle's: read-only, as it was then. */
export function HistoryPanel(props: { bundle?: { id: string; name: string; openTrace: (id: string) => void } }) {
  const offline = props.bundle;
  const base = () => (offline ? `/api/bundles/${offline.id}/history` : machineBase());
  const [f, setF] = useState<Filter>({ group: 0, severity: 0, back_s: 0, actor: "", text: "" });
  const [rows, setRows] = useState<HistoryEntry[]>([]);
  const [total, setTotal] = useState(0);
  const [error, setError] = useState("");
  const [note, setNote] = useState("");
  const [typed, setTyped] = useState({ actor: "", text: "" });
  const [saved, setSaved] = useState<TraceInfo | null>(null);
  const [lastS, setLastS] = useState(60);
  const [flight, setFlight] = useState<FlightRecorderStatus | null>(null);
  useEffect(() => {
    if (!machineId.value || offline) return;
    const load = () =>
      http.get<FlightRecorderStatus>(`/api/machines/${encodeURIComponent(machineId.value)}/flight-recorder`).then(setFlight, () => setFlight(null));
    void load();
    const t = setInterval(() => void load(), 5000); // how far back it reaches grows
    return () => clearInterval(t);
  }, [machineId.value, saved]);
  useEffect(() => {
    const t = setTimeout(() => setF((old) => (old.actor === typed.actor && old.text === typed.text ? old : { ...old, ...typed })), TYPING_MS);
    return () => clearTimeout(t);
  }, [typed.actor, typed.text]);

  async function load(older: boolean) {
    if (!machineId.value && !offline) return;
    const q = query(f);
    q.set("limit", String(PAGE));
    const last = rows[rows.length - 1];
    if (older && last) {
      q.set("before_unix", String(last.time_unix));
      q.set("before_id", last.id);
    }
    try {
      const page = await http.get<HistoryPage>(`${base()}?${q}`);
      setRows((now) => (older ? [...now, ...page.rows] : page.rows));
      setTotal(page.total);
      setError("");
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }
  useEffect(() => void load(false), [f, machineId.value, offline?.id]);

  // entries written while the panel is open arrive over the socket
  const live = liveHistory.value;
  useEffect(() => {
    if (offline) return;
    const fresh = live.filter((e) => matches(e, f));
    if (!fresh.length) return;
    setRows((now) => {
      const known = new Map(fresh.map((e) => [e.id, e])); // an entry again: updated (a trace)
      const kept = now.map((r) => known.get(r.id) ?? r);
      const have = new Set(now.map((r) => r.id));
      const add = fresh.filter((e) => !have.has(e.id));
      if (add.length) setTotal((t) => t + add.length);
      return [...add, ...kept].sort(newestFirst);
    });
  }, [live]);

  async function addNote(e: Event) {
    e.preventDefault();
    if (!note.trim()) return;
    try {
      await http.post<HistoryEntry>(`${base()}/notes`, { text: note.trim() });
      setNote(""); // the entry comes back over the socket
      setError("");
    } catch (err) {
      setError(err instanceof ApiError ? err.refusal.message : String(err));
    }
  }

  async function saveLast() {
    try {
      setSaved(await http.post<TraceInfo>(`/api/machines/${encodeURIComponent(machineId.value)}/flight-recorder/save`, { seconds: lastS }));
      setError("");
    } catch (err) {
      setError(err instanceof ApiError ? err.refusal.message : String(err));
    }
  }

  const set = (patch: Partial<Filter>) => setF({ ...f, ...patch });
  const exportUrl = (format: "csv" | "json") => {
    const q = query(f);
    q.set("format", format);
    return `${base()}/export?${q}`;
  };
  return (
    <Panel title={offline ? `History of ${offline.name} (offline, read-only)` : `History: machine ${machineId.value}`} id={offline ? "bundle-history" : "history"}>
      <div class="row history-filters">
        <label>
          Show{" "}
          <select data-testid="history-kind" value={String(f.group)} onChange={(e) => set({ group: Number((e.target as HTMLSelectElement).value) })}>
            {GROUPS.map((g, i) => (
              <option key={g.label} value={String(i)}>
                {g.label}
              </option>
            ))}
          </select>
        </label>
        <label>
          Severity{" "}
          <select data-testid="history-severity" value={String(f.severity)} onChange={(e) => set({ severity: Number((e.target as HTMLSelectElement).value) })}>
            {SEVERITIES.map((s, i) => (
              <option key={s.label} value={String(i)}>
                {s.label}
              </option>
            ))}
          </select>
        </label>
        <label>
          Time{" "}
          <select data-testid="history-range" value={String(f.back_s)} onChange={(e) => set({ back_s: Number((e.target as HTMLSelectElement).value) })}>
            {TIME_RANGES.map((r) => (
              <option key={r.back_s} value={String(r.back_s)}>
                {r.label}
              </option>
            ))}
          </select>
        </label>
        <label>
          User{" "}
          <input data-testid="history-actor" size={10} value={typed.actor} placeholder="any"
            onInput={(e) => setTyped({ ...typed, actor: (e.target as HTMLInputElement).value })} />
        </label>
        <label>
          Text{" "}
          <input type="search" data-testid="history-text" size={16} value={typed.text} placeholder="in what happened"
            onInput={(e) => setTyped({ ...typed, text: (e.target as HTMLInputElement).value })} />
        </label>
        <button type="button" class="secondary" data-testid="history-refresh" onClick={() => void load(false)}>
          Refresh
        </button>
        {offline ? null : (
          <>
            <a class="button secondary" data-testid="history-csv" href={exportUrl("csv")} download>
              Export CSV
            </a>
            <a class="button secondary" data-testid="history-json" href={exportUrl("json")} download>
              JSON
            </a>
            {me.value?.guest ? null : <a class="button secondary" data-testid="history-bundle" download
              href={`/api/machines/${encodeURIComponent(machineId.value)}/bundle`}
              title="one zip for an expert elsewhere: lists, versions and the diff against the baseline, this history, the alarms' flight-recorder traces (.rrd and CSV), the status">
              Diagnostic bundle
            </a>}
          </>
        )}
      </div>
      {may("note") && !offline ? (
        <form class="row history-note" onSubmit={(e) => void addNote(e)}>
          <input data-testid="history-note-input" maxLength={2000} value={note} aria-label="logbook entry"
            placeholder="Logbook entry, e.g. replaced the encoder cable of X"
            onInput={(e) => setNote((e.target as HTMLInputElement).value)} />
          <button type="submit" data-testid="history-note-add" disabled={!note.trim()}>
            Add to logbook
          </button>
        </form>
      ) : null}
      {may("capture") && !offline ? (
        <div class="row history-flight">
          <span class="hint" data-testid="flight-status"
            title={flight ? `full rate for the last ${fmt(flight.full_rate_s, 0)} s, one sample in ${flight.decimation} cycles beyond; ${fmt(flight.bytes / 1e6, 1)} MB` : ""}>
            Flight recorder{flight ? `: holds the last ${span(flight.held_s)}${flight.held_s < flight.reach_s - 1 ? ` (up to ${span(flight.reach_s)} once the machine has run that long)` : ""}, saves ${fmt(flight.before_s, 0)} s before and ${fmt(flight.after_s, 0)} s after each job error` : ""}
          </span>
          <label>
            Save the last{" "}
            <input type="number" data-testid="flight-seconds" min={1} max={3600} step={1} value={lastS} style="width: 5em"
              onInput={(e) => setLastS(Number((e.target as HTMLInputElement).value))} />{" "}
            s
          </label>
          <button type="button" class="secondary" data-testid="flight-save" disabled={!(lastS > 0)} onClick={() => void saveLast()}>
            Save as trace
          </button>
          {saved ? (
            <span data-testid="flight-saved">
              saved “{saved.name}”{" "}
              <button type="button" class="link" data-testid="flight-saved-open" onClick={() => openTrace(saved.id)}>
                open in the scope
              </button>
            </span>
          ) : null}
        </div>
      ) : null}
      {error ? (
        <p class="refusal" role="alert" data-testid="history-error">
          {error}
        </p>
      ) : null}
      <div class="table-scroll">
        <table class="audit history" data-testid="history-table">
          <thead>
            <tr>
              <th title={Intl.DateTimeFormat().resolvedOptions().timeZone}>Time (local)</th>
              <th class="num" title="the machine's simulated time (from 0 at each power-on) and its build">Machine t [s]</th>
              <th>Kind</th>
              <th>Who</th>
              <th>What</th>
              <th>Outcome</th>
            </tr>
          </thead>
          <tbody>
            {rows.map((r) => (
              <tr key={r.id} data-testid="history-row" data-id={r.id} data-kind={r.kind} class={`${r.severity} ${r.kind}`}>
                <td class="num">{wallTime(r.time_unix)}</td>
                <td class="num" title={r.epoch !== null ? `build ${r.epoch}` : ""}>
                  {r.sim_t_s !== null ? fmt(r.sim_t_s, 3) : "—"}
                </td>
                <td data-testid="history-kind-cell">{KIND_WORDS[r.kind] ?? r.kind}</td>
                <td data-testid="history-actor-cell">{r.actor || "NC"}</td>
                <td class="wrap" data-testid="history-text-cell">
                  {r.code !== null ? <b>{r.code} </b> : null}
                  {r.axis ? `[${r.axis}] ` : ""}
                  {r.text}
                  {r.cause ? <div class="hint" data-testid="history-cause">{r.cause}</div> : null}
                </td>
                <td class="wrap" data-testid="history-outcome-cell">
                  {r.outcome && r.outcome !== "ok" ? <b>✗ {r.outcome}</b> : r.outcome}
                  {r.trace ? (
                    <span class="history-trace">
                      <button type="button" class="link" data-testid="history-trace-open" title="the flight recorder's trace of the seconds around it"
                        onClick={() => (offline ? offline.openTrace(r.trace!) : openTrace(r.trace!))}>
                        {offline ? "▶ trace" : "▶ trace in the scope"}
                      </button>{" "}
                      {may("capture") ? (
                        <a href={`/api/traces/${r.trace}/viewer`} target="_blank" rel="noopener" data-testid="history-trace-rerun">
                          Rerun
                        </a>
                      ) : (
                        <a href={`/api/traces/${r.trace}/trace.rrd`} download data-testid="history-trace-rrd">
                          .rrd
                        </a>
                      )}
                    </span>
                  ) : null}
                </td>
              </tr>
            ))}
          </tbody>
        </table>
        {!rows.length ? <p class="hint">Nothing in the history matches.</p> : null}
      </div>
      <div class="row apart">
        <span class="hint" data-testid="history-count">
          {rows.length} of {total} entries
        </span>
        <button type="button" class="secondary" data-testid="history-older" disabled={rows.length >= total} onClick={() => void load(true)}>
          Load older
        </button>
      </div>
    </Panel>
  );
}
