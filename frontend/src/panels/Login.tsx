// The login screen, shown instead of the HMI while nobody is logged in.
import { useRef, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { login } from "../state/auth";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";

export function Login() {
  const [name, setName] = useState("");
  const [password, setPassword] = useState("");
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const passwordInput = useRef<HTMLInputElement>(null);

  async function submit(e: Event) {
    e.preventDefault();
    setBusy(true);
    try {
      await login(name.trim(), password); // on success the HMI replaces this screen
    } catch (err) {
      setRefusal(err instanceof ApiError ? err.refusal : { message: String(err), problems: [] });
      setPassword(""); // type it again, the name stays
      setBusy(false);
      passwordInput.current?.focus();
    }
  }

  return (
    <div class="login-page">
      <header class="topbar">
        <span class="brand">Inbetrieb</span>
      </header>
      <div class="login">
        <Panel title="Log in" id="login">
          <form class="login-form" data-testid="login-form" onSubmit={(e) => void submit(e)}>
            <label>
              Name
              <input data-testid="login-name" name="username" autocomplete="username" required autofocus maxLength={64}
                value={name} onInput={(e) => setName((e.target as HTMLInputElement).value)} />
            </label>
            <label>
              Password
              <input data-testid="login-password" name="password" type="password" autocomplete="current-password"
                required maxLength={256} ref={passwordInput}
                value={password} onInput={(e) => setPassword((e.target as HTMLInputElement).value)} />
            </label>
            <RefusalLine refusal={refusal} id="login-error" />
            <button type="submit" data-testid="login-submit" disabled={busy}>
              Log in
            </button>
          </form>
          <p class="hint">
            On the computer running the service, open the one-time login link <code>make run</code> printed.
          </p>
        </Panel>
      </div>
    </div>
  );
}
