// Share the machine by link: a read-only view for someone without an account (its live view,
// history and traces), valid for the hours chosen, revocable; who watches through each link.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { ShareCreated, ShareLink } from "../api/types";
import { machineId } from "../state/session";
import { Panel } from "../ui/Panel";
import { useNewest } from "../ui/useNewest";

const VALIDITY: { label: string; hours: number }[] = [
  { label: "1 hour", hours: 1 },
  { label: "8 hours", hours: 8 },
  { label: "1 day", hours: 24 },
  { label: "3 days", hours: 72 },
  { label: "1 week", hours: 168 },
];

const base = () => `/api/machines/${encodeURIComponent(machineId.value)}/share`;
const at = (t: number) => new Date(t * 1000).toLocaleString();

export function SharePanel() {
  const [hours, setHours] = useState(8);
  const [label, setLabel] = useState("");
  const [made, setMade] = useState<ShareCreated | null>(null);
  const [links, showLinks] = useNewest<ShareLink[]>([]);
  const [error, setError] = useState("");
  const load = () => showLinks(http.get<ShareLink[]>(base()).catch(() => []));
  useEffect(() => {
    void load();
    const t = setInterval(() => void load(), 5000); // who watches, expiries
    return () => clearInterval(t);
  }, [machineId.value]);

  async function create(e: Event) {
    e.preventDefault();
    try {
      setMade(await http.post<ShareCreated>(base(), { hours, label: label.trim() }));
      setLabel("");
      setError("");
      void load();
    } catch (err) {
      setError(err instanceof ApiError ? err.refusal.message : String(err));
    }
  }

  async function revoke(id: string) {
    try {
      await http.del<ShareLink>(`${base()}/${id}`);
      if (made?.link.id === id) setMade(null);
      void load();
    } catch (err) {
      setError(err instanceof ApiError ? err.refusal.message : String(err));
    }
  }

  return (
    <Panel title="Share this machine by link" id="share">
      <p class="hint">
        Anyone with the link watches this machine without an account — live view, history, traces — and can change
        nothing, until it expires or you revoke it. Every opening is recorded.
      </p>
      <form class="row" onSubmit={(e) => void create(e)}>
        <label>
          Valid for{" "}
          <select data-testid="share-hours" value={String(hours)} onChange={(e) => setHours(Number((e.target as HTMLSelectElement).value))}>
            {VALIDITY.map((v) => (
              <option key={v.hours} value={String(v.hours)}>
                {v.label}
              </option>
            ))}
          </select>
        </label>
        <label>
          For{" "}
          <input data-testid="share-label" maxLength={60} size={20} value={label} placeholder="e.g. the drive maker's service"
            onInput={(e) => setLabel((e.target as HTMLInputElement).value)} />
        </label>
        <button type="submit" data-testid="share-create">
          Create link
        </button>
      </form>
      {made ? (
        <div class="row share-made" data-testid="share-made">
          <input class="share-url" readOnly value={made.url} data-testid="share-url" aria-label="the share link"
            onFocus={(e) => (e.target as HTMLInputElement).select()} />
          <button type="button" class="secondary" data-testid="share-copy" onClick={() => void navigator.clipboard?.writeText(made.url)}>
            Copy
          </button>
          <span class="hint">shown once: pass it on now</span>
        </div>
      ) : null}
      {error ? (
        <p class="refusal" role="alert" data-testid="share-error">
          {error}
        </p>
      ) : null}
      {links.length ? (
        <table class="audit" data-testid="share-links">
          <thead>
            <tr>
              <th>For</th>
              <th>Made</th>
              <th>Ends</th>
              <th class="num">Opened</th>
              <th class="num">Watching</th>
              <th />
            </tr>
          </thead>
          <tbody>
            {links.map((l) => (
              <tr key={l.id} data-testid="share-link" data-id={l.id} class={l.active ? "" : "ended"}>
                <td>{l.label || "—"}</td>
                <td>
                  {at(l.created_unix)} by {l.created_by}
                </td>
                <td>{l.revoked_unix ? `revoked ${at(l.revoked_unix)} by ${l.revoked_by}` : l.active ? at(l.expires_unix) : `expired ${at(l.expires_unix)}`}</td>
                <td class="num">{l.uses}</td>
                <td class="num" data-testid="share-watching">{l.watching}</td>
                <td>
                  {l.active ? (
                    <button type="button" class="secondary" data-testid="share-revoke" onClick={() => void revoke(l.id)}>
                      Revoke
                    </button>
                  ) : null}
                </td>
              </tr>
            ))}
          </tbody>
        </table>
      ) : null}
    </Panel>
  );
}
