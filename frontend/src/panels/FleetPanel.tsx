// Every machine at a glance — reachable or being rebuilt, mode and state, job errors in
// force and the last alarm, who holds control, who watches, loop overruns — and the alarms
// across the machines, newest first. A row opens that machine.
import { useEffect, useState } from "preact/hooks";
import { ApiError, http } from "../api/http";
import type { Fleet } from "../api/types";
import { tab } from "../state/route";
import { machineId, selectMachine } from "../state/session";
import { Panel } from "../ui/Panel";

const REFRESH_MS = 3000;
const at = (t: number) => new Date(t * 1000).toLocaleTimeString();

function open(mid: string, where: "Operate" | "History") {
  if (mid !== machineId.value) selectMachine(mid);
  tab.value = where;
}

export function FleetPanel() {
  const [fleet, setFleet] = useState<Fleet | null>(null);
  const [error, setError] = useState("");
  useEffect(() => {
    const load = () =>
      http.get<Fleet>("/api/fleet").then(
        (f) => {
          setFleet(f);
          setError("");
        },
        (e: unknown) => setError(e instanceof ApiError ? e.refusal.message : String(e)),
      );
    void load();
    const t = setInterval(() => void load(), REFRESH_MS);
    return () => clearInterval(t);
  }, []);
  const names = new Map((fleet?.machines ?? []).map((m) => [m.id, m.name]));
  return (
    <>
      <Panel title="Fleet: every machine at a glance" id="fleet">
        {error ? (
          <p class="refusal" role="alert">
            {error}
          </p>
        ) : null}
        <div class="table-scroll">
          <table class="audit fleet" data-testid="fleet-table">
            <thead>
              <tr>
                <th>Machine</th>
                <th>Worker</th>
                <th>Mode</th>
                <th>State</th>
                <th>Job errors in force</th>
                <th>Last alarm</th>
                <th>Control</th>
                <th class="num">Watching</th>
                <th class="num">Overruns/min</th>
              </tr>
            </thead>
            <tbody>
              {(fleet?.machines ?? []).map((m) => (
                <tr key={m.id} data-testid="fleet-row" data-id={m.id}
                  class={m.reachable !== "running" ? "warning" : m.active_errors.length ? "error" : ""}>
                  <td>
                    <button type="button" class="link" data-testid="fleet-open" onClick={() => open(m.id, "Operate")}>
                      {m.name}
                    </button>
                    {m.seat ? <span class="hint"> (class seat)</span> : null}
                  </td>
                  <td data-testid="fleet-reachable">{m.reachable === "running" ? "✓" : m.reachable}</td>
                  <td>{m.mode}</td>
                  <td data-testid="fleet-state">{m.state}</td>
                  <td data-testid="fleet-errors">{m.active_errors.join(", ") || "—"}</td>
                  <td class="wrap">
                    {m.last_alarm ? (
                      <button type="button" class="link" onClick={() => open(m.id, "History")} title={m.last_alarm.text}>
                        {m.last_alarm.code} at {at(m.last_alarm.time_unix)}
                      </button>
                    ) : (
                      "—"
                    )}
                  </td>
                  <td>{m.holder ?? "free"}</td>
                  <td class="num" data-testid="fleet-viewers">
                    {m.viewers}
                    {m.guests ? ` (${m.guests} by link)` : ""}
                  </td>
                  <td class="num">{m.overruns_per_min ?? "—"}</td>
                </tr>
              ))}
            </tbody>
          </table>
        </div>
      </Panel>
      <Panel title="Alarms across the machines" id="fleet-alarms">
        {fleet?.alarms.length ? (
          <table class="audit history" data-testid="fleet-alarms">
            <tbody>
              {fleet.alarms.map((a) => (
                <tr key={a.id} class="error">
                  <td class="num">{new Date(a.time_unix * 1000).toLocaleString()}</td>
                  <td>
                    <button type="button" class="link" onClick={() => open(fleet.machine_of[a.id], "History")}>
                      {names.get(fleet.machine_of[a.id]) ?? fleet.machine_of[a.id]}
                    </button>
                  </td>
                  <td class="wrap">
                    <b>{a.code}</b> {a.axis ? `[${a.axis}] ` : ""}
                    {a.text}
                    {a.cause ? <div class="hint">{a.cause}</div> : null}
                  </td>
                </tr>
              ))}
            </tbody>
          </table>
        ) : (
          <p class="hint">No job error on any machine yet.</p>
        )}
      </Panel>
    </>
  );
}
