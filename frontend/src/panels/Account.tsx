// The user's account, opened from the name in the top bar: their API tokens (create one,
// shown once; revoke), and for admins the users (add, change role or password, remove).
import { signal } from "@preact/signals";
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { Refusal, Role, TokenCreated, TokenInfo, UserInfo } from "../api/types";
import { loadMe, me } from "../state/auth";
import { Panel } from "../ui/Panel";
import { useNewest } from "../ui/useNewest";
import { RefusalLine } from "../ui/useCommand";

/** Whether the account dialog is open. */
export const accountOpen = signal(false);

const ROLES: Role[] = ["observer", "operator", "instructor", "admin"];
const MIN_PASSWORD = 8; // as api/auth.py MIN_PASSWORD

function refusalOf(e: unknown): Refusal {
  return e instanceof ApiError ? e.refusal : { message: String(e), problems: [] };
}

function when(t: number | null | undefined): string {
  return t ? new Date(t * 1000).toLocaleString() : "never";
}

/** Run a request; its refusal (or null) goes to `setRefusal`, then `after` runs on success. */
async function attempt(setRefusal: (r: Refusal | null) => void, work: () => Promise<unknown>, after: () => void) {
  try {
    await work();
    setRefusal(null);
    after();
  } catch (e) {
    setRefusal(refusalOf(e));
  }
}

export function AccountDialog() {
  const user = me.value;
  if (!accountOpen.value || !user) return null;
  const admin = user.actions.includes("users");
  return (
    <div class="account-backdrop" onClick={(e) => e.target === e.currentTarget && (accountOpen.value = false)}>
      <div class="account-dialog" role="dialog" aria-modal="true" aria-label="Account">
        <Panel
          title={`Account: ${user.name} (${user.role})`}
          id="account"
          actions={
            <button type="button" class="secondary" data-testid="account-close" onClick={() => (accountOpen.value = false)}>
              Close
            </button>
          }
        >
          <Tokens />
          {admin ? <Users self={user.name} /> : null}
        </Panel>
      </div>
    </div>
  );
}

function Tokens() {
  const [tokens, showTokens] = useNewest<TokenInfo[]>([]);
  const [label, setLabel] = useState("");
  const [created, setCreated] = useState<TokenCreated | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const reload = () => void attempt(setRefusal, () => showTokens(http.get<TokenInfo[]>("/api/auth/tokens")), () => {});
  useEffect(reload, []);
  const create = (e: Event) => {
    e.preventDefault();
    void attempt(
      setRefusal,
      async () => setCreated(await http.post<TokenCreated>("/api/auth/tokens", { label })),
      () => {
        setLabel("");
        reload();
      },
    );
  };
  return (
    <section class="account-section" data-testid="account-tokens">
      <h3>API tokens</h3>
      <p class="hint">For scripts: send <code>Authorization: Bearer &lt;token&gt;</code>. A token acts as you.</p>
      <table class="account-table">
        <thead>
          <tr>
            <th>Label</th>
            <th>Id</th>
            <th>Created</th>
            <th>Last used</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {tokens.map((t) => (
            <tr key={t.id} data-testid="token-row" data-token-id={t.id}>
              <td>{t.label || "—"}</td>
              <td>
                <code>{t.id}</code>
              </td>
              <td>{when(t.created_unix)}</td>
              <td>{when(t.last_used_unix)}</td>
              <td>
                <button
                  type="button"
                  class="secondary"
                  data-testid="token-revoke"
                  onClick={() =>
                    void attempt(setRefusal, () => http.del(`/api/auth/tokens/${encodeURIComponent(t.id)}`), () => {
                      if (created?.info.id === t.id) setCreated(null);
                      reload();
                    })
                  }
                >
                  Revoke
                </button>
              </td>
            </tr>
          ))}
        </tbody>
      </table>
      {tokens.length === 0 ? <p class="hint" data-testid="tokens-none">No API tokens.</p> : null}
      <form class="account-form" onSubmit={create}>
        <label>
          Label{" "}
          <input data-testid="token-label" value={label} maxLength={100} placeholder="what it is for" required
            onInput={(e) => setLabel((e.target as HTMLInputElement).value)} />
        </label>
        <button type="submit" data-testid="token-create">
          Create token
        </button>
      </form>
      {created ? (
        <div class="token-once" data-testid="token-created">
          <p>Copy this token now: it is not shown again.</p>
          <code data-testid="token-secret">{created.token}</code>{" "}
          <button type="button" class="secondary" data-testid="token-copy"
            onClick={() => void navigator.clipboard?.writeText(created.token).catch(() => {})}>
            Copy
          </button>
        </div>
      ) : null}
      <RefusalLine refusal={refusal} id="tokens-error" />
    </section>
  );
}

function Users(props: { self: string }) {
  const [users, showUsers] = useNewest<UserInfo[]>([]);
  const [name, setName] = useState("");
  const [role, setRole] = useState<Role>("operator");
  const [password, setPassword] = useState("");
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const reload = () => void attempt(setRefusal, () => showUsers(http.get<UserInfo[]>("/api/users")), () => {});
  useEffect(reload, []);
  const path = (n: string) => `/api/users/${encodeURIComponent(n)}`;
  const add = (e: Event) => {
    e.preventDefault();
    void attempt(setRefusal, () => http.post("/api/users", { name, role, password }), () => {
      setName("");
      setPassword("");
      reload();
    });
  };
  const change = (n: string, body: { role?: Role; password?: string }) =>
    void attempt(setRefusal, () => http.patch(path(n), body), () => {
      reload();
      if (n === props.self) void loadMe(); // one's own role changed
    });
  return (
    <section class="account-section" data-testid="account-users">
      <h3>Users</h3>
      <table class="account-table">
        <thead>
          <tr>
            <th>Name</th>
            <th>Role</th>
            <th>Created</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {users.map((u) => (
            <tr key={u.name} data-testid="user-row" data-user={u.name}>
              <td>{u.name}</td>
              <td>
                <select data-testid="user-role-select" value={u.role} aria-label={`role of ${u.name}`}
                  onChange={(e) => change(u.name, { role: (e.target as HTMLSelectElement).value as Role })}>
                  {ROLES.map((r) => (
                    <option key={r} value={r}>
                      {r}
                    </option>
                  ))}
                </select>
              </td>
              <td>{when(u.created_unix)}</td>
              <td>
                <button type="button" class="secondary" data-testid="user-password"
                  onClick={() => {
                    const pw = prompt(`New password for ${u.name} (at least ${MIN_PASSWORD} characters; their sessions end)`);
                    if (pw) change(u.name, { password: pw });
                  }}>
                  Set password
                </button>{" "}
                <button type="button" class="secondary" data-testid="user-remove" disabled={u.name === props.self}
                  title={u.name === props.self ? "you cannot remove yourself" : "remove the user, their sessions and tokens"}
                  onClick={() => void attempt(setRefusal, () => http.del(path(u.name)), reload)}>
                  Remove
                </button>
              </td>
            </tr>
          ))}
        </tbody>
      </table>
      <form class="account-form" onSubmit={add}>
        <input data-testid="user-new-name" value={name} placeholder="name" required
          onInput={(e) => setName((e.target as HTMLInputElement).value)} />
        <select data-testid="user-new-role" aria-label="role of the new user" value={role} onChange={(e) => setRole((e.target as HTMLSelectElement).value as Role)}>
          {ROLES.map((r) => (
            <option key={r} value={r}>
              {r}
            </option>
          ))}
        </select>
        <input data-testid="user-new-password" type="password" value={password} minLength={MIN_PASSWORD} required
          placeholder={`password (≥ ${MIN_PASSWORD} characters)`} autocomplete="new-password"
          onInput={(e) => setPassword((e.target as HTMLInputElement).value)} />
        <button type="submit" data-testid="user-add">
          Add user
        </button>
      </form>
      <RefusalLine refusal={refusal} id="users-error" />
    </section>
  );
}
