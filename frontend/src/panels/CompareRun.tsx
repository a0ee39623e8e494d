// Before/after: an earlier stored run of the same assistant on the same axis (or plane) to lay
// over this one, and the figures both have side by side with the change.
import { useEffect, useState } from "preact/hooks";
import { http } from "../api/http";
import type { AssistResult, AssistRun, AssistRunInfo } from "../api/types";
import { machineUrl } from "../state/session";
import { fmt } from "../ui/format";

const when = (t: number) => new Date(t * 1000).toLocaleTimeString();

/** "#12 10:41:03": how an earlier run is named in legends and tables. */
export const runLabel = (run: AssistRun): string => `#${run.id} ${when(run.time_unix)}`;

/** A choice of earlier runs of `result`'s assistant on its axis (and what `matches` asks
 * more); `onPick` gets the chosen run, or null. */
export function CompareWith(props: {
  result: AssistResult;
  matches?: (run: AssistRunInfo) => boolean;
  onPick: (run: AssistRun | null) => void;
  testid: string;
}) {
  const r = props.result;
  const axis = String(r.inputs.axis ?? "");
  const [runs, setRuns] = useState<AssistRunInfo[]>([]);
  const [pick, setPick] = useState("");
  useEffect(() => {
    http.get<AssistRunInfo[]>(machineUrl("/assist/runs?limit=50")).then(
      // earlier runs: not the one shown
      (all) =>
        setRuns(all.filter((x) => x.id !== r.run_id && x.assistant === r.assistant && x.axis === axis && (props.matches?.(x) ?? true))),
      () => setRuns([]),
    );
  }, [r]);
  useEffect(() => {
    if (!pick) return props.onPick(null);
    http.get<AssistRun>(machineUrl(`/assist/runs/${pick}`)).then(props.onPick, () => props.onPick(null));
  }, [pick]);
  return (
    <label class="assist-field bode-compare">
      <span>Compare with</span>
      <select data-testid={props.testid} value={pick} onChange={(e) => setPick((e.target as HTMLSelectElement).value)}>
        <option value="">— an earlier run to lay over this one —</option>
        {runs.map((x) => (
          <option key={x.id} value={String(x.id)}>
            #{x.id} {when(x.time_unix)} {x.live ? "on the machine" : "on a copy"}: {x.summary}
          </option>
        ))}
      </select>
    </label>
  );
}

/** The figures both runs have, this run's beside the earlier one's with the change. */
export function FigureDeltas(props: { now: AssistResult; before: AssistResult; label: string; skip?: Set<string> }) {
  const before = new Map(props.before.figures.map((f) => [f.name, f]));
  const rows = props.now.figures.filter((f) => before.has(f.name) && !props.skip?.has(f.name));
  if (!rows.length) return null;
  return (
    <table class="bode-deltas" data-testid="bode-deltas">
      <thead>
        <tr>
          <th>figure</th>
          <th>this run</th>
          <th>{props.label}</th>
          <th>change</th>
        </tr>
      </thead>
      <tbody>
        {rows.map((f) => {
          const b = before.get(f.name)!;
          const d = f.value - b.value;
          // a share only of a magnitude (not of an angle, nor across a change of sign)
          const share = f.unit !== "°" && b.value > 0 && f.value > 0;
          const pct = share ? ` (${d >= 0 ? "+" : "−"}${fmt(Math.abs((d / b.value) * 100), 1)} %)` : "";
          return (
            <tr key={f.name} data-figure={f.name}>
              <td>{f.text || f.name}</td>
              <td>{fmt(f.value, 3)} {f.unit}</td>
              <td>{fmt(b.value, 3)} {b.unit}</td>
              <td>{d >= 0 ? "+" : "−"}{fmt(Math.abs(d), 3)} {f.unit}{pct}</td>
            </tr>
          );
        })}
      </tbody>
    </table>
  );
}
