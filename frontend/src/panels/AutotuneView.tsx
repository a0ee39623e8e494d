// The speed-loop autotune's answer: the template's margins beside what the new values are
// predicted to keep and what the loop measured again with them keeps, and the open loop's Bode
// plot as it is, as predicted and as measured again.
import type { AssistResult } from "../api/types";
import { figure } from "../state/assist";
import { fmt } from "../ui/format";
import { BodeChart } from "./BodeChart";

// the prediction last, dashed: drawn over the measurement it should match
const CURVES: [string, string][] = [
  ["now", "as it is"],
  ["measured again", "measured again"],
  ["predicted", "predicted (dashed)"],
];

/** One pseudo run per curve (magnitude_db@now … → magnitude_db), for the Bode plot. */
function curves(r: AssistResult): { runs: AssistResult[]; labels: string[] } {
  const runs: AssistResult[] = [];
  const labels: string[] = [];
  for (const [tag, label] of CURVES) {
    const series = r.series.filter((s) => s.name.endsWith(`@${tag}`)).map((s) => ({ ...s, name: s.name.split("@")[0] }));
    if (!series.length) continue;
    runs.push({ ...r, series, figures: runs.length ? [] : r.figures.filter((f) => f.name === "crossover_hz" || f.name === "notch_hz") });
    labels.push(label);
  }
  return { runs, labels };
}

function Row(props: { what: string; target: number | null; before: number | null; predicted: number | null; achieved: number | null; unit: string; atLeast: boolean }) {
  const ok = props.target === null || props.achieved === null || !props.atLeast || props.achieved >= props.target - 0.05;
  const cell = (v: number | null) => (v === null ? "—" : `${fmt(v, 1)} ${props.unit}`);
  return (
    <tr data-row={props.what}>
      <td>{props.what}</td>
      <td class="num">{props.target === null ? "—" : `≥ ${fmt(props.target, 0)} ${props.unit}`}</td>
      <td class="num">{cell(props.before)}</td>
      <td class="num">{cell(props.predicted)}</td>
      <td class={`num ${ok ? "" : "warn"}`}>{cell(props.achieved)}</td>
    </tr>
  );
}

export function AutotuneView(props: { result: AssistResult }) {
  const r = props.result;
  const { runs, labels } = curves(r);
  return (
    <div class="autotune-view">
      <table class="meas-table autotune-check" data-testid="autotune-check">
        <thead>
          <tr>
            <th />
            <th class="num">template</th>
            <th class="num">as it is</th>
            <th class="num">predicted</th>
            <th class="num">measured again</th>
          </tr>
        </thead>
        <tbody>
          <Row what="phase margin" target={figure(r, "target_pm_deg")} before={figure(r, "pm_now_deg")} predicted={figure(r, "pm_deg")}
            achieved={figure(r, "pm_achieved_deg")} unit="°" atLeast />
          <Row what="gain margin" target={figure(r, "target_gm_db")} before={figure(r, "gm_now_db")} predicted={figure(r, "gm_db")}
            achieved={figure(r, "gm_achieved_db")} unit="dB" atLeast />
          <Row what="bandwidth" target={null} before={figure(r, "bandwidth_now_hz")} predicted={figure(r, "bandwidth_hz")}
            achieved={figure(r, "bandwidth_achieved_hz")} unit="Hz" atLeast={false} />
        </tbody>
      </table>
      {runs.length ? (
        <BodeChart result={runs[0]} earlier={runs.slice(1)} labels={labels} dashed={labels.findIndex((l) => l.startsWith("predicted"))} />
      ) : null}
    </div>
  );
}
