// Diagnostic bundles opened on this service: open the zip an engineer on site made, and each
// opened bundle's page (BundlePage: the machine as it was then, read-only).
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { BundleDetail, BundleInfo } from "../api/types";
import { may } from "../state/control";
import { openBundle } from "../state/route";
import { Panel } from "../ui/Panel";

const at = (t: number) => new Date(t * 1000).toLocaleString();

export function BundlesPanel() {
  const [bundles, setBundles] = useState<BundleInfo[]>([]);
  const [error, setError] = useState("");
  useEffect(() => void http.get<BundleInfo[]>("/api/bundles").then(setBundles, () => setBundles([])), []);

  async function open(file: File) {
    try {
      const d = await http.postFile<BundleDetail>("/api/bundles", file, "application/zip");
      setError("");
      openBundle(d.id);
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  return (
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
              <a href={`#bundle/${b.id}`} data-testid="bundle-show">
                {b.manifest.machine_name}
              </a>{" "}
              made {at(b.manifest.created_unix)} by {b.manifest.created_by} (Inbetrieb {b.manifest.service_version}), opened {at(b.opened_unix)}
            </li>
          ))}
        </ul>
      ) : (
        <p class="hint">No bundle opened here yet. A bundle is made in a machine's History (“Diagnostic bundle”).</p>
      )}
    </Panel>
  );
}
