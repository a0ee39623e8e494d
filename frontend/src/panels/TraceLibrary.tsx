// The trace library: stored traces with machine, trigger, time and notes; show, overlay,
// rename, annotate, delete, download (CSV, .rrd), open in the Rerun viewer; import a CSV.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import { may } from "../state/control";
import type { TraceInfo } from "../api/types";
import { library, overlayId, refreshLibrary, shownId, followNewest } from "../state/scope";
import { Panel } from "../ui/Panel";

export const when = (unix: number) => new Date(unix * 1000).toLocaleString();

export function TraceLinks(props: { id: string }) {
  const { id } = props;
  return (
    <span class="trace-links">
      <a href={`/api/traces/${id}/csv`} download data-testid={`csv-${id}`}>CSV</a>
      <a href={`/api/traces/${id}/trace.rrd`} download data-testid={`rrd-${id}`}>.rrd</a>
      <a href={`/api/traces/${id}/viewer`} target="_blank" rel="noreferrer" data-testid={`viewer-${id}`}>Rerun viewer</a>
    </span>
  );
}

function Row(props: { t: TraceInfo; onError: (m: string) => void }) {
  const { t } = props;
  const [editing, setEditing] = useState(false);
  const [name, setName] = useState(t.name);
  const [notes, setNotes] = useState(t.notes);
  async function act(f: () => Promise<unknown>) {
    try {
      await f();
      await refreshLibrary();
    } catch (e) {
      props.onError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }
  return (
    <tr data-testid={`trace-${t.id}`} class={shownId.value === t.id ? "shown" : ""}>
      <td>
        {editing ? (
          <>
            <input value={name} aria-label="name" data-testid="trace-name-input" onInput={(e) => setName((e.target as HTMLInputElement).value)} />
            <textarea value={notes} aria-label="notes" rows={2} onInput={(e) => setNotes((e.target as HTMLTextAreaElement).value)} />
            <button type="button" data-testid="trace-rename-ok"
              onClick={() => void act(async () => {
                await http.patch(`/api/traces/${t.id}`, { name, notes });
                setEditing(false);
              })}>
              ✓
            </button>
          </>
        ) : (
          <>
            <b>{t.name}</b>
            {t.notes ? <div class="hint">{t.notes}</div> : null}
          </>
        )}
      </td>
      <td>{t.machine_name}</td>
      <td>{t.trigger || "—"}</td>
      <td>{when(t.created_unix)}</td>
      <td>{t.params_changed}</td>
      <td class="row-actions">
        <button type="button" onClick={() => { followNewest.value = false; shownId.value = t.id; }}>show</button>
        <button type="button" aria-pressed={overlayId.value === t.id} data-testid={`overlay-${t.id}`}
          onClick={() => (overlayId.value = overlayId.value === t.id ? "" : t.id)}>
          overlay
        </button>
        {may("capture") ? <button type="button" onClick={() => setEditing(!editing)}>rename</button> : null}
        <TraceLinks id={t.id} />
        <button type="button" class="link danger" data-testid={`delete-${t.id}`}
          disabled={!may("delete_trace")} title={may("delete_trace") ? undefined : "deleting traces takes the role operator or above"}
          onClick={() => confirm(`Delete "${t.name}"?`) && void act(async () => {
            await http.del(`/api/traces/${t.id}`);
            if (overlayId.value === t.id) overlayId.value = "";
          })}>
          delete
        </button>
      </td>
    </tr>
  );
}

export function TraceLibrary() {
  const [error, setError] = useState("");
  useEffect(() => void refreshLibrary().catch(() => undefined), []);

  async function importFile(e: Event) {
    const input = e.target as HTMLInputElement;
    const file = input.files?.[0];
    input.value = "";
    if (!file) return;
    try {
      const name = encodeURIComponent(file.name.replace(/\.csv$/i, ""));
      const info = await http.postText<TraceInfo>(`/api/traces/import?name=${name}`, await file.text(), "text/csv");
      await refreshLibrary();
      overlayId.value = info.id;
      setError("");
    } catch (err) {
      setError(String(err instanceof Error ? err.message : err));
    }
  }

  return (
    <Panel title="Trace library" id="trace-library"
      actions={
        may("capture") ? (
          <label class="file-button">
            Import CSV…
            <input type="file" accept=".csv,text/csv" data-testid="trace-import" onChange={(e) => void importFile(e)} />
          </label>
        ) : null
      }>
      {error ? <p class="refusal" role="alert">{error}</p> : null}
      {library.value.length ? (
        <div class="trace-table-wrap">
        <table class="trace-table">
          <thead>
            <tr>
              <th>name / notes</th>
              <th>machine</th>
              <th>trigger</th>
              <th>captured</th>
              <th title="parameters that differed from their defaults">params ≠ default</th>
              <th />
            </tr>
          </thead>
          <tbody>
            {library.value.map((t) => (
              <Row key={t.id} t={t} onError={setError} />
            ))}
          </tbody>
        </table>
        </div>
      ) : (
        <p class="hint">No stored traces yet: save a capture, or import a CSV.</p>
      )}
    </Panel>
  );
}
