// The login screen, shown instead of the HMI while nobody is logged in; to a class seat's
// student whose class the instructor ended, their final result first (the service knows the
// seat by the ended session's cookie) until they are done with it.
import type { ComponentChildren } from "preact";
import { useEffect, useRef, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { Refusal, SeatResult } from "../api/types";
import { login, shareEnded } from "../state/auth";
import { forgetSeat, wasSeat } from "../state/exercise";
import { fmt } from "../ui/format";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";

/** Seat time as m:ss (h:mm:ss from an hour). */
function clock(s: number): string {
  const t = Math.max(0, Math.floor(s));
  const [h, m, sec] = [Math.floor(t / 3600), Math.floor((t % 3600) / 60), t % 60];
  const pad = (n: number) => String(n).padStart(2, "0");
  return h ? `${h}:${pad(m)}:${pad(sec)}` : `${m}:${pad(sec)}`;
}

export function Login() {
  // undefined: still asking whether this browser's session was an ended class's seat
  const [result, setResult] = useState<SeatResult | null | undefined>(undefined);
  useEffect(() => {
    http.get<SeatResult>("/api/auth/seat-result").then(setResult, () => setResult(null));
  }, []);
  if (result === undefined) return <p class="hint login-wait">Connecting to the service…</p>;
  if (result) return <ClassEnded result={result} onDone={() => setResult(null)} />;
  if (shareEnded.value) return <ShareEnded />;
  return <LoginForm />;
}

/** A guest whose share link ended: what happened, and no login form (a guest has no
 * account); someone with one can still log in. */
function ShareEnded() {
  return (
    <LoginFrame>
      <Panel title="The share link has ended" id="share-ended-panel">
        <p role="alert" data-testid="share-ended">
          The share link you were watching through has ended: it expired or was revoked. Ask whoever sent it for a new one.
        </p>
        <p class="hint">
          Have an account on this service? <button type="button" class="link" onClick={() => (shareEnded.value = false)}>Log in</button>
        </p>
      </Panel>
    </LoginFrame>
  );
}

/** The student's result as a page of its own to keep (their login is gone after "Done"). */
function resultFile(r: SeatResult): string {
  const esc = (v: unknown) => String(v).replace(/[&<>"]/g, (ch) => `&#${ch.charCodeAt(0)};`);
  const rows: [string, string][] = [
    ["Student", r.student],
    ["Class", `${r.title} (${r.class_id}), seat ${r.seat}`],
    ["Exercise", r.exercise],
    ["Ended", new Date(r.ended_unix * 1000).toLocaleString()],
    ["Score", `${fmt(r.score, 0)} of ${fmt(r.max_points, 0)} points`],
    ["Checks passed", `${r.checks_passed} of ${r.checks_total}`],
    ["Hints taken", String(r.hints_taken)],
    ["Seat time", clock(r.seat_time_s)],
  ];
  const checks = r.stages
    .map(
      (st) =>
        `<h2>${esc(st.title)}: ${esc(fmt(st.score, 1))} of ${esc(fmt(st.max_points, 0))} points</h2><ul>` +
        st.checks.map((k) => `<li>${k.first_passed_s !== null ? "✓" : "✗"} ${esc(k.text)} (${esc(fmt(k.earned, 1))} of ${esc(fmt(k.points, 0))})</li>`).join("") +
        "</ul>",
    )
    .join("");
  const html =
    `<!doctype html><meta charset="utf-8"><title>Result: ${esc(r.student)}</title>` +
    `<body style="font:15px/1.5 sans-serif;max-width:40em;margin:2em auto"><h1>Inbetrieb: class result</h1><table>` +
    rows.map(([k, v]) => `<tr><th style="text-align:left;padding-right:1em">${esc(k)}</th><td>${esc(v)}</td></tr>`).join("") +
    `</table>${checks}</body>`;
  return `data:text/html;charset=utf-8,${encodeURIComponent(html)}`;
}

/** The end of a class for its student: the seat's final result; "Done" ends the old session
 * (the service forgets the result) and shows the login. */
function ClassEnded(props: { result: SeatResult; onDone: () => void }) {
  const r = props.result;
  const done = () => void http.post<null>("/api/auth/logout", {}).finally(props.onDone);
  return (
    <LoginFrame>
        <Panel title="The class has ended" id="class-ended">
          <p>
            {r.student}, your instructor ended the class <b>{r.title}</b> at {new Date(r.ended_unix * 1000).toLocaleTimeString()}.
            Your seat's machine has gone; this is your result{r.exercise !== r.title ? <> in <i>{r.exercise}</i></> : null}:
          </p>
          <table class="dense" data-testid="class-result">
            <tbody>
              <tr>
                <th>Score</th>
                <td><b data-testid="result-score">{fmt(r.score, 0)}</b> of {fmt(r.max_points, 0)} points</td>
              </tr>
              <tr>
                <th>Checks passed</th>
                <td><b data-testid="result-checks">{r.checks_passed}</b> of {r.checks_total}</td>
              </tr>
              <tr>
                <th>Hints taken</th>
                <td data-testid="result-hints">{r.hints_taken}</td>
              </tr>
              <tr>
                <th>Seat time</th>
                <td>{clock(r.seat_time_s)}</td>
              </tr>
            </tbody>
          </table>
          <div data-testid="result-checks-list">
            {r.stages.map((st) => (
              <div key={st.exercise}>
                {r.stages.length > 1 ? <h3>{st.title}: {fmt(st.score, 1)} of {fmt(st.max_points, 0)} points</h3> : null}
                <ul class="plain">
                  {st.checks.map((k) => (
                    <li key={k.id} class={k.first_passed_s !== null ? "ok" : ""}>
                      {k.first_passed_s !== null ? "✓" : "✗"} {k.text} <span class="hint">({fmt(k.earned, 1)} of {fmt(k.points, 0)})</span>
                    </li>
                  ))}
                </ul>
              </div>
            ))}
          </div>
          <p class="hint">Your instructor has your checks, traces and commands for the debrief.</p>
          <p>
            <a class="button secondary" data-testid="class-result-save" href={resultFile(r)}
              download={`result-${r.class_id}-seat-${r.seat}.html`}>
              Keep my result (a page to save or print)
            </a>
          </p>
          <button type="button" data-testid="class-ended-done" onClick={done}>
            Done
          </button>
        </Panel>
    </LoginFrame>
  );
}

function LoginForm() {
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
      forgetSeat();
    } catch (err) {
      setRefusal(err instanceof ApiError ? err.refusal : { message: String(err), problems: [] });
      setPassword(""); // type it again, the name stays
      setBusy(false);
      passwordInput.current?.focus();
    }
  }

  return (
    <LoginFrame>
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
          <p class="hint" data-testid="login-help">
            {wasSeat()
              ? "A class seat logs in by the link your instructor gives you (good once): ask them for a new one."
              : "Students of a class: open the login link your instructor gave you. On the computer running the service, the one-time link it printed at its start logs in too."}
          </p>
        </Panel>
    </LoginFrame>
  );
}

/** The page around the login and the class-ended panel: the brand and one centred panel. */
function LoginFrame(props: { children: ComponentChildren }) {
  return (
    <div class="login-page">
      <header class="topbar">
        <span class="brand">Inbetrieb</span>
      </header>
      <div class="login">{props.children}</div>
    </div>
  );
}
