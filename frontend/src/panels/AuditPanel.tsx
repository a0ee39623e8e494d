// The whole service's audit trail, for admins: who did what to any machine, and logins,
// failed logins, users and tokens, newest first, filtered; older pages on demand; the same
// filter as CSV; the hash chain's check. (A machine's own rows are in its History.)
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { AuditKind, AuditPage, AuditRecord, AuditVerification } from "../api/types";
import { TIME_RANGES, TYPING_MS, wallTime } from "../ui/logFilters";
import { Panel } from "../ui/Panel";

const PAGE = 100;
const KINDS: AuditKind[] = [
  "command",
  "assist",
  "parameter",
  "version",
  "control",
  "simulation",
  "machine",
  "trace",
  "program",
  "recording",
  "report",
  "login",
  "login_failed",
  "logout",
  "user",
  "token",
];

interface Filter {
  kind: AuditKind | "";
  actor: string;
  text: string;
  back_s: number;
}

/** The query of a filter (since is counted back from now, when the query is made). */
function query(f: Filter): URLSearchParams {
  const q = new URLSearchParams();
  if (f.kind) q.set("kind", f.kind);
  if (f.actor.trim()) q.set("actor", f.actor.trim());
  if (f.text.trim()) q.set("text", f.text.trim());
  if (f.back_s) q.set("since_unix", String(Math.floor(Date.now() / 1000 - f.back_s)));
  return q;
}



export function AuditPanel() {
  const [f, setF] = useState<Filter>({ kind: "", actor: "", text: "", back_s: 0 });
  const [rows, setRows] = useState<AuditRecord[]>([]);
  const [total, setTotal] = useState(0);
  const [error, setError] = useState("");
  const [verified, setVerified] = useState<AuditVerification | null>(null);
  // the user and text fields as typed; the filter follows them once typing pauses
  const [typed, setTyped] = useState({ actor: "", text: "" });
  useEffect(() => {
    const t = setTimeout(() => setF((old) => (old.actor === typed.actor && old.text === typed.text ? old : { ...old, ...typed })), TYPING_MS);
    return () => clearTimeout(t);
  }, [typed.actor, typed.text]);

  async function load(older: boolean) {
    const q = query(f);
    q.set("limit", String(PAGE));
    if (older && rows.length) q.set("before_seq", String(rows[rows.length - 1].seq));
    try {
      const page = await http.get<AuditPage>(`/api/audit?${q}`);
      setRows(older ? [...rows, ...page.rows] : page.rows);
      setTotal(page.total);
      setError("");
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  useEffect(() => void load(false), [f]);

  async function verify() {
    try {
      setVerified(await http.get<AuditVerification>("/api/audit/verify"));
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  const set = (patch: Partial<Filter>) => setF({ ...f, ...patch });
  return (
    <Panel title="Audit trail: whole service" id="audit">
      <div class="row audit-filters">
        <label>
          Kind{" "}
          <select data-testid="audit-kind" value={f.kind} onChange={(e) => set({ kind: (e.target as HTMLSelectElement).value as AuditKind })}>
            <option value="">all</option>
            {KINDS.map((k) => (
              <option key={k} value={k}>
                {k}
              </option>
            ))}
          </select>
        </label>
        <label>
          User{" "}
          <input data-testid="audit-actor" size={12} value={typed.actor} placeholder="any"
            onInput={(e) => setTyped({ ...typed, actor: (e.target as HTMLInputElement).value })} />
        </label>
        <label>
          Text{" "}
          <input type="search" data-testid="audit-text" size={18} value={typed.text} placeholder="in action or outcome"
            onInput={(e) => setTyped({ ...typed, text: (e.target as HTMLInputElement).value })} />
        </label>
        <label>
          Time{" "}
          <select data-testid="audit-range" value={String(f.back_s)}
            onChange={(e) => set({ back_s: Number((e.target as HTMLSelectElement).value) })}>
            {TIME_RANGES.map((r) => (
              <option key={r.back_s} value={String(r.back_s)}>
                {r.label}
              </option>
            ))}
          </select>
        </label>
        <button type="button" class="secondary" data-testid="audit-refresh" onClick={() => void load(false)}>
          Refresh
        </button>
        <a class="button secondary" data-testid="audit-csv" href={`/api/audit.csv?${query(f)}`} download="audit.csv">
          Export CSV
        </a>
        <button type="button" class="secondary" data-testid="audit-verify" onClick={() => void verify()}>
          Verify chain
        </button>
      </div>
      {verified ? (
        <p class={verified.ok ? "audit-verified ok" : "audit-verified bad"} data-testid="audit-verification" role="status">
          {verified.ok ? "✓" : "✗"} {verified.message}
        </p>
      ) : null}
      {error ? (
        <p class="refusal" role="alert" data-testid="audit-error">
          {error}
        </p>
      ) : null}
      <div class="table-scroll">
        <table class="audit">
          <thead>
            <tr>
              <th>Time</th>
              <th>User</th>
              <th>Machine</th>
              <th>Kind</th>
              <th>Action</th>
              <th>Outcome</th>
            </tr>
          </thead>
          <tbody>
            {rows.map((r) => {
              const refused = r.outcome !== "ok";
              return (
                <tr key={r.seq} data-testid="audit-row" data-seq={r.seq} data-kind={r.kind} class={refused ? "refused" : ""}>
                  <td class="num">{wallTime(r.time_unix)}</td>
                  <td data-testid="audit-actor-cell">{r.actor}</td>
                  <td>{r.machine || "—"}</td>
                  <td data-testid="audit-kind-cell">{r.kind}</td>
                  <td class="wrap" data-testid="audit-action-cell">{r.action}</td>
                  <td class="wrap" data-testid="audit-outcome-cell">{refused ? <b>✗ {r.outcome}</b> : "ok"}</td>
                </tr>
              );
            })}
          </tbody>
        </table>
        {!rows.length ? <p class="hint">No audit row matches.</p> : null}
      </div>
      <div class="row apart">
        <span class="hint" data-testid="audit-count">
          {rows.length} of {total} rows
        </span>
        <button type="button" class="secondary" data-testid="audit-older" disabled={rows.length >= total}
          onClick={() => void load(true)}>
          Load older
        </button>
      </div>
    </Panel>
  );
}
