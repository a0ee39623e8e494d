// Diagnostic bundles opened here: the expert at home opens the zip an engineer on site made
// and sees that machine as it was, read-only — its history, the difference to its baseline,
// its parameter lists, the flight recorder's traces of its alarms (in the scope, in Rerun).
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { BundleDetail, BundleInfo } from "../api/types";
import { may } from "../state/control";
import { openTrace } from "../state/route";
import { Panel } from "../ui/Panel";
import { HistoryPanel } from "./HistoryPanel";
import { DiffTable } from "./Versions";

const at = (t: number) => new Date(t * 1000).toLocaleString();

export function BundlesPanel() {
  const [bundles, setBundles] = useState<BundleInfo[]>([]);
  const [shown, setShown] = useState<BundleDetail | null>(null);
  const [error, setError] = useState("");
  const load = () => http.get<BundleInfo[]>("/api/bundles").then(setBundles, () => setBundles([]));
  useEffect(() => void load(), []);

  async function open(file: File) {
    try {
      const d = await http.postFile<BundleDetail>("/api/bundles", file, "application/zip");
      setShown(d);
      setError("");
      void load();
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  async function show(id: string) {
    try {
      setShown(await http.get<BundleDetail>(`/api/bundles/${id}`));
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  const m = shown?.manifest;
  return (
    <>
      <Panel title="Diagnostic bundles (offline machines)" id="bundles">
        {may("capture") ? (
          <label class="row">
            Open a bundle (.zip){" "}
            <input type="file" accept=".zip,application/zip" data-testid="bundle-file"
              onChange={(e) => {
                const f = (e.target as HTMLInputElement).files?.[0];
                if (f) void open(f);
              }} />
          </label>
        ) : null}
        {error ? (
          <p class="refusal" role="alert" data-testid="bundle-error">
            {error}
          </p>
        ) : null}
        {bundles.length ? (
          <ul class="bundles" data-testid="bundle-list">
            {bundles.map((b) => (
              <li key={b.id}>
                <button type="button" class="link" data-testid="bundle-show" onClick={() => void show(b.id)}>
                  {b.manifest.machine_name}
                </button>{" "}
                made {at(b.manifest.created_unix)} by {b.manifest.created_by} (Inbetrieb {b.manifest.service_version}), opened {at(b.opened_unix)}
              </li>
            ))}
          </ul>
        ) : (
          <p class="hint">No bundle opened here yet. A bundle is made in a machine's History (“Diagnostic bundle”).</p>
        )}
      </Panel>
      {shown && m ? (
        <>
          <Panel title={`Offline: ${m.machine_name} as on ${at(m.created_unix)}`} id="bundle">
            <p class="hint" data-testid="bundle-summary">
              Made by {m.created_by} on Inbetrieb {m.service_version}: {m.history_entries} history entries, {m.traces.length} alarm
              traces, {m.lists.length} parameter lists. Read-only.
            </p>
            <h3>Parameter lists</h3>
            <p>
              {m.lists.map((name) => (
                <a key={name} class="button secondary" href={`/api/bundles/${shown.id}/lists/${name}`} download={`${m.machine_name}_${name}`}>
                  {name}
                </a>
              ))}
            </p>
            <h3>Alarm traces</h3>
            {shown.trace_infos.length ? null : <p class="hint">None: no job error had a flight-recorder trace.</p>}
            <ul data-testid="bundle-traces">
              {shown.trace_infos.map((t) => (
                <li key={t.id}>
                  <button type="button" class="link" data-testid="bundle-trace-open" onClick={() => openTrace(t.id)}>
                    ▶ {t.name} (captured {at(t.created_unix)})
                  </button>{" "}
                  <a href={`/api/traces/${t.id}/viewer`} target="_blank" rel="noopener">
                    Rerun
                  </a>
                </li>
              ))}
            </ul>
            <h3>Against its baseline</h3>
            <div data-testid="bundle-diff">{shown.diff ? <DiffTable diff={shown.diff.changes} /> : <p class="hint">It had no baseline.</p>}</div>
          </Panel>
          <HistoryPanel bundle={{ id: shown.id, name: m.machine_name }} />
        </>
      ) : null}
    </>
  );
}
