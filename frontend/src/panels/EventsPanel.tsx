// Job errors and events with code, axis, time and message; filter by text or errors only.
import { useState } from "preact/hooks";
import { events } from "../state/events";
import { Panel } from "../ui/Panel";
import { fmt } from "../ui/format";

export function EventsPanel(props: { compact?: boolean }) {
  const [query, setQuery] = useState("");
  const [errorsOnly, setErrorsOnly] = useState(false);
  const q = query.trim().toLowerCase();
  const list = events.value
    .filter((e) => (!errorsOnly || e.error) && (!q || `${e.code} ${e.axis} ${e.message}`.toLowerCase().includes(q)))
    .slice()
    .reverse()
    .slice(0, props.compact ? 6 : 500);
  return (
    <Panel
      title="Events"
      id={props.compact ? "events-recent" : "events"}
      actions={
        props.compact ? null : (
          <span class="row">
            <input type="search" placeholder="filter" value={query} aria-label="filter events"
              onInput={(e) => setQuery((e.target as HTMLInputElement).value)} />
            <label>
              <input type="checkbox" checked={errorsOnly} onChange={() => setErrorsOnly(!errorsOnly)} /> errors only
            </label>
          </span>
        )
      }
    >
      <div class="table-scroll">
        <table class="events" data-testid="event-table">
          <thead>
            <tr>
              <th class="num">t [s]</th>
              <th>Kind</th>
              <th class="num">Code</th>
              <th>Axis</th>
              <th>Message</th>
            </tr>
          </thead>
          <tbody>
            {list.map((e) => (
              <tr key={`${e.cycle}:${e.code}:${e.axis}`} class={e.error ? "error" : ""}>
                <td class="num">{fmt(e.t_s, 3)}</td>
                <td>{e.error ? "✖ error" : "ℹ event"}</td>
                <td class="num">{e.code}</td>
                <td>{e.axis || "channel"}</td>
                <td>{e.message}</td>
              </tr>
            ))}
          </tbody>
        </table>
      </div>
    </Panel>
  );
}
