// An opened diagnostic bundle on its own page (`#bundle/<id>`): the machine an engineer on
// site bundled, as it was then and read-only — what it is, its alarm traces (one on screen,
// the erroring axis drawn), its difference to its baseline, its parameter lists and versions,
// its history. Nothing here is the live machine: the page says so and leads back.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { BundleDetail } from "../api/types";
import { may } from "../state/control";
import { bundlePage, closeBundle, showBundleTrace } from "../state/route";
import { type LoadedTrace, loadTrace } from "../state/scope";
import { Panel } from "../ui/Panel";
import { HistoryPanel } from "./HistoryPanel";
import { TopBar } from "./TopBar";
import { TraceView } from "./TraceView";
import { DiffTable } from "./Versions";

const at = (t: number) => new Date(t * 1000).toLocaleString();

/** The alarm trace the page shows, loaded; the first when the address names none. */
function AlarmTrace(props: { id: string }) {
  const [trace, setTrace] = useState<LoadedTrace | null>(null);
  const [error, setError] = useState("");
  useEffect(() => {
    setTrace(null);
    loadTrace(props.id).then(setTrace, (e: unknown) => setError(e instanceof ApiError ? e.refusal.message : String(e)));
  }, [props.id]);
  if (error) return <p class="refusal">{error}</p>;
  return trace ? <TraceView trace={trace} overlay={null} /> : <p class="hint">Loading the trace…</p>;
}

export function BundlePage() {
  const page = bundlePage.value!;
  const [shown, setShown] = useState<BundleDetail | null>(null);
  const [error, setError] = useState("");
  useEffect(() => {
    setShown(null);
    http.get<BundleDetail>(`/api/bundles/${page.id}`).then(
      (d) => {
        setShown(d);
        setError("");
      },
      (e: unknown) => setError(e instanceof ApiError && e.status === 404 ? "This bundle is not opened on this service (or was removed)." : String(e)),
    );
  }, [page.id]);

  async function remove() {
    if (!confirm("Remove this offline machine and its traces from this service? The zip you opened stays where it is.")) return;
    try {
      await http.del(`/api/bundles/${page.id}`);
      closeBundle();
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  const m = shown?.manifest;
  const traceId = page.trace || shown?.trace_infos[0]?.id || "";
  return (
    <div class="app">
      <div class="head">
        <TopBar machine={false} />
        <div class="offline-strip" role="status" data-testid="offline-strip">
          <b>Offline machine</b> — a diagnostic bundle, read-only: nothing here acts on a live machine.
          <button type="button" class="secondary" data-testid="bundle-back" onClick={closeBundle}>
            ◂ Live machines
          </button>
        </div>
      </div>
      <main class="bundle-page">
        {error ? (
          <p class="refusal" role="alert" data-testid="bundle-error">
            {error}
          </p>
        ) : null}
        {shown && m ? (
          <>
            <Panel title={`${m.machine_name} as on ${at(m.created_unix)}`} id="bundle"
              actions={may("delete_trace") ? (
                <button type="button" class="secondary" data-testid="bundle-remove" onClick={() => void remove()}>
                  Remove from this service
                </button>
              ) : null}>
              <p class="hint" data-testid="bundle-summary">
                Made by {m.created_by} on Inbetrieb {m.service_version}, opened here {at(shown.opened_unix)}: {m.history_entries} history
                entries, {m.traces.length} alarm traces, {m.lists.length} parameter lists, {shown.versions.length} versions.
              </p>
              <p class="row">
                Parameter lists:{" "}
                {m.lists.map((name) => (
                  <a key={name} class="button secondary" href={`/api/bundles/${shown.id}/lists/${name}`} download={`${m.machine_name}_${name}`}>
                    {name}
                  </a>
                ))}
              </p>
            </Panel>
            <Panel title="Alarm traces (flight recorder)" id="bundle-alarm-traces">
              {shown.trace_infos.length ? (
                <ul class="bundle-traces" data-testid="bundle-traces">
                  {shown.trace_infos.map((t) => (
                    <li key={t.id}>
                      <button type="button" class={t.id === traceId ? "link current" : "link"} data-testid="bundle-trace-open"
                        aria-current={t.id === traceId} onClick={() => showBundleTrace(t.id)}>
                        ▶ {t.name} (captured {at(t.created_unix)})
                      </button>{" "}
                      <a href={`/api/traces/${t.id}/viewer`} target="_blank" rel="noopener">
                        Rerun
                      </a>
                    </li>
                  ))}
                </ul>
              ) : (
                <p class="hint">None: no job error had a flight-recorder trace.</p>
              )}
              {traceId ? <AlarmTrace id={traceId} /> : null}
            </Panel>
            <Panel title="Against its baseline" id="bundle-diff-panel">
              <div data-testid="bundle-diff">{shown.diff ? <DiffTable diff={shown.diff.changes} /> : <p class="hint">It had no baseline.</p>}</div>
              {shown.versions.length ? (
                <table class="param-diff" data-testid="bundle-versions">
                  <thead>
                    <tr><th>version</th><th>made</th><th>by</th><th>values</th><th>note</th></tr>
                  </thead>
                  <tbody>
                    {shown.versions.map((v) => (
                      <tr key={v.id}>
                        <td>{v.name}{v.baseline ? " (baseline)" : ""}</td>
                        <td>{at(v.created_unix)}</td>
                        <td>{v.created_by}</td>
                        <td class="num">{v.values}</td>
                        <td class="wrap">{v.note}</td>
                      </tr>
                    ))}
                  </tbody>
                </table>
              ) : null}
            </Panel>
            <HistoryPanel bundle={{ id: shown.id, name: m.machine_name, openTrace: showBundleTrace }} />
          </>
        ) : !error ? (
          <p class="hint">Opening the bundle…</p>
        ) : null}
      </main>
    </div>
  );
}
