// The commissioning report of the machine: the stored assistant runs, the traces to plot in
// it, Open report (a printable page in a new tab) and Download PDF, and the sign-off (name,
// function, remark; recorded with the account and time, in the audit trail).
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { AssistRunInfo, Refusal, SignOff, SignOffRequest, TraceInfo } from "../api/types";
import { loadCatalogue, titleOf } from "../state/assist";
import { me } from "../state/auth";
import { may } from "../state/control";
import { machineId, machineUrl } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";

const RUNS_SHOWN = 20;
const REFRESH_MS = 3000; // a run ends in the assistant's panel: the list follows within this

const when = (unix: number) => new Date(unix * 1000).toLocaleString();

function refusalOf(e: unknown): Refusal {
  return e instanceof ApiError ? e.refusal : { message: e instanceof Error ? e.message : String(e), problems: [] };
}

/** The report's URL with the chosen traces (`?trace=A&trace=B`). */
function reportUrl(path: string, traces: string[]): string {
  const q = new URLSearchParams(traces.map((t) => ["trace", t]));
  return machineUrl(path) + (traces.length ? `?${q.toString()}` : "");
}

export function ReportPanel() {
  const mid = machineId.value;
  const [runs, setRuns] = useState<AssistRunInfo[]>([]);
  const [traces, setTraces] = useState<TraceInfo[]>([]);
  const [chosen, setChosen] = useState<string[]>([]);
  const [signOffs, setSignOffs] = useState<SignOff[]>([]);
  const [form, setForm] = useState<SignOffRequest>({ name: "", role: "", remark: "" });
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [printing, setPrinting] = useState(false);
  const maySign = may("sign_off");

  async function refresh() {
    if (!mid) return;
    try {
      const [r, t, s] = await Promise.all([
        http.get<AssistRunInfo[]>(machineUrl(`/assist/runs?limit=${RUNS_SHOWN}`)),
        http.get<TraceInfo[]>(`/api/traces?machine=${encodeURIComponent(mid)}`),
        http.get<SignOff[]>(machineUrl("/report/sign-offs")),
      ]);
      setRuns(r);
      setTraces(t);
      setSignOffs(s);
    } catch {
      // the connection lamp says it; the next refresh tries again
    }
  }
  useEffect(() => void loadCatalogue(), []);
  useEffect(() => {
    setChosen([]);
    setRefusal(null);
    void refresh();
    const id = setInterval(() => void refresh(), REFRESH_MS);
    return () => clearInterval(id);
  }, [mid]);

  const toggle = (id: string) => setChosen(chosen.includes(id) ? chosen.filter((c) => c !== id) : [...chosen, id]);

  async function downloadPdf() {
    setPrinting(true);
    setRefusal(null);
    try {
      const pdf = await http.bytes(reportUrl("/report.pdf", chosen));
      const a = document.createElement("a");
      a.href = URL.createObjectURL(new Blob([pdf], { type: "application/pdf" }));
      a.download = `commissioning-report-${mid}.pdf`;
      a.click();
      setTimeout(() => URL.revokeObjectURL(a.href), 60_000);
    } catch (e) {
      setRefusal(refusalOf(e));
    } finally {
      setPrinting(false);
    }
  }

  async function signOff() {
    setRefusal(null);
    try {
      await http.post<SignOff>(machineUrl("/report/sign-off"), form);
      setForm({ name: "", role: "", remark: "" });
      await refresh();
    } catch (e) {
      setRefusal(refusalOf(e));
    }
  }

  const set = (patch: Partial<SignOffRequest>) => setForm({ ...form, ...patch });
  const last = signOffs[signOffs.length - 1];
  return (
    <Panel title="Commissioning report" id="report">
      <div class="report-panel">
        <div>
          <h3>Stored runs</h3>
          {runs.length ? (
            <div class="table-wrap">
            <table class="report-runs" data-testid="report-runs">
              <thead>
                <tr>
                  <th>#</th>
                  <th>Assistant</th>
                  <th>Axis</th>
                  <th>Result</th>
                  <th>By, when</th>
                </tr>
              </thead>
              <tbody>
                {runs.map((r) => (
                  <tr key={r.id} data-testid={`report-run-${r.id}`}>
                    <td class="num">{r.id}</td>
                    <td>
                      {titleOf(r.assistant)}
                      <div class="hint">{r.live ? "live" : "on a copy"}</div>
                    </td>
                    <td>{r.axis}</td>
                    <td class={r.ok ? "" : "report-fault"}>{r.summary}</td>
                    <td>
                      {r.user}
                      <div class="hint">{when(r.time_unix)}</div>
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
            </div>
          ) : (
            <p class="hint" data-testid="report-no-runs">No assistant has run on this machine yet: every run is kept for the report.</p>
          )}
        </div>
        <div>
          <h3>Traces to include</h3>
          {traces.length ? (
            <ul class="report-traces" data-testid="report-traces">
              {traces.map((t) => (
                <li key={t.id}>
                  <label>
                    <input type="checkbox" data-testid={`report-trace-${t.id}`} checked={chosen.includes(t.id)} onChange={() => toggle(t.id)} />
                    <b>{t.name || t.id}</b> <span class="hint">{t.trigger || "—"}, {when(t.created_unix)}</span>
                  </label>
                </li>
              ))}
            </ul>
          ) : (
            <p class="hint">No stored trace of this machine (save one in the Scope's library).</p>
          )}
          <div class="row">
            <a class="button" data-testid="report-open" href={mid ? reportUrl("/report", chosen) : undefined} target="_blank" rel="noreferrer">
              Open report
            </a>
            <button type="button" class="secondary" data-testid="report-pdf" disabled={printing || !mid} onClick={() => void downloadPdf()}>
              {printing ? "Printing…" : "Download PDF"}
            </button>
          </div>
          <p class="hint">
            The machine, who commissioned it, every run with its figures and plots, the differences against the baseline, the chosen traces, an
            audit excerpt and the sign-off; A4, one section a page.
          </p>
        </div>
        <div>
          <h3>Sign-off</h3>
          <p data-testid="report-signed" class={last ? "" : "hint"}>
            {last ? (
              <>
                Signed off by <b>{last.name}</b>
                {last.role ? `, ${last.role}` : ""} on {when(last.time_unix)}
              </>
            ) : (
              "Not signed off yet."
            )}
          </p>
          <label class="assist-field">
            <span>Name</span>
            <input data-testid="sign-name" value={form.name} maxLength={100} disabled={!maySign} onInput={(e) => set({ name: (e.target as HTMLInputElement).value })} />
          </label>
          <label class="assist-field">
            <span>Function</span>
            <input data-testid="sign-role" value={form.role} maxLength={100} placeholder="commissioning engineer" disabled={!maySign}
              onInput={(e) => set({ role: (e.target as HTMLInputElement).value })} />
          </label>
          <label class="assist-field">
            <span>Remark</span>
            <textarea data-testid="sign-remark" value={form.remark} rows={2} maxLength={2000} disabled={!maySign}
              onInput={(e) => set({ remark: (e.target as HTMLTextAreaElement).value })} />
          </label>
          <button type="button" data-testid="sign-off" disabled={!maySign || !form.name.trim()}
            title={maySign ? "" : `a user in the role ${me.value?.role ?? ""} may not sign off`} onClick={() => void signOff()}>
            Sign off
          </button>
        </div>
      </div>
      <RefusalLine refusal={refusal} id="report-refusal" />
    </Panel>
  );
}
