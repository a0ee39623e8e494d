// The position loop gain sweep's answer (nc_sim/assist/loop_gain.py): per kv the step's
// overshoot and settling and the ramp's lag against v/kv, the kv proposed (the highest meeting
// the target), and the responses per kv and the figures over kv as plots.
import type { AssistResult, AssistSeries } from "../api/types";
import { figure } from "../state/assist";
import { fmt } from "../ui/format";
import { AssistChart } from "./AssistChart";

/** The kv of the sweep (1/s), ascending, from the per-kv figures `name@kv`. */
export function sweptKvs(r: AssistResult): number[] {
  const kvs = r.figures.filter((f) => f.name.startsWith("overshoot_pct@")).map((f) => Number(f.name.split("@")[1]));
  return kvs.sort((a, b) => a - b);
}


const at = (r: AssistResult, name: string, kv: number) => figure(r, `${name}@${kv}`);

function meets(r: AssistResult, kv: number): boolean {
  const os = at(r, "overshoot_pct", kv);
  const st = at(r, "settling_ms", kv);
  const osMax = figure(r, "overshoot_max_pct") ?? 0;
  const stMax = figure(r, "settle_max_ms") ?? 0;
  return os !== null && st !== null && os <= osMax && st <= stMax;
}

const byPrefix = (r: AssistResult, prefix: string): AssistSeries[] => r.series.filter((s) => s.name.startsWith(prefix));
const kvLabel = (s: AssistSeries) => `kv ${s.name.split("@")[1]}/s`;

export function LoopGainView(props: { result: AssistResult }) {
  const r = props.result;
  const kvs = sweptKvs(r);
  const now = figure(r, "kv");
  const chosen = figure(r, "kv_new");
  const osMax = figure(r, "overshoot_max_pct") ?? 0;
  const stMax = figure(r, "settle_max_ms") ?? 0;
  const step = figure(r, "step") ?? 0;
  const unit = r.figures.find((f) => f.name === "step")?.unit ?? "mm";
  const steps = byPrefix(r, "step@");
  const ramps = byPrefix(r, "ramp_lag@");
  const os = r.series.find((s) => s.name === "overshoot_vs_kv");
  const st = r.series.find((s) => s.name === "settling_vs_kv");
  const target = `overshoot ≤ ${fmt(osMax, 1)} %, settling ≤ ${fmt(stMax, 0)} ms`;
  return (
    <div class="assist-figures" data-testid="loop-gain">
      {chosen !== null ? (
        <p class="assist-check ok" data-testid="assist-check" data-ok="1">
          ✓ kv = <b data-testid="loop-gain-kv-new">{fmt(chosen, 2)}</b> /s: the highest of the sweep with {target}
          {now !== null ? ` (now ${fmt(now, 2)} /s)` : ""}
        </p>
      ) : (
        <p class="assist-check off" data-testid="assist-check" data-ok="0">
          No kv of the sweep meets {target}: see the notes
        </p>
      )}
      <div class="loop-gain-table">
      <table class="meas-table" data-testid="loop-gain-table">
        <thead>
          <tr>
            <th class="num">kv [1/s]</th>
            <th class="num">Overshoot [%]</th>
            <th class="num">[{unit}]</th>
            <th class="num">Settling [ms]</th>
            <th class="num">Lag [{unit}]</th>
            <th class="num">v/kv [{unit}]</th>
            <th>Target</th>
          </tr>
        </thead>
        <tbody>
          {kvs.map((kv) => (
            <tr key={kv} data-testid={`loop-gain-row-${kv}`} class={kv === chosen ? "chosen" : ""}>
              <td class="num">
                {fmt(kv, 2)}
                {kv === now ? <span class="hint"> (now)</span> : null}
              </td>
              <td class="num">{fmt(at(r, "overshoot_pct", kv), 2)}</td>
              <td class="num">{fmt(at(r, "overshoot", kv), 4)}</td>
              <td class="num">{at(r, "settling_ms", kv) === null ? "not settled" : fmt(at(r, "settling_ms", kv), 0)}</td>
              <td class="num">{fmt(at(r, "lag", kv), 4)}</td>
              <td class="num">{fmt(at(r, "lag_expected", kv), 4)}</td>
              <td>{meets(r, kv) ? "✓ meets" : "✗"}</td>
            </tr>
          ))}
        </tbody>
      </table>
      </div>
      <div class="loop-gain-plots">
        {steps.length ? (
          <div class="assist-plot">
            <AssistChart series={steps[0]} more={steps.slice(1)} label={kvLabel} yLabel="step: actual − start"
              levels={[{ label: "target", value: step }]} testid="loop-gain-steps" />
          </div>
        ) : null}
        {ramps.length ? (
          <div class="assist-plot">
            <AssistChart series={ramps[0]} more={ramps.slice(1)} label={kvLabel} yLabel="ramp: lag" levels={[]} testid="loop-gain-ramps" />
          </div>
        ) : null}
        {os ? (
          <div class="assist-plot">
            <AssistChart series={os} label={() => "step overshoot"} yLabel="overshoot" xLabel="kv [1/s]"
              levels={[{ label: "target", value: osMax }]} testid="loop-gain-overshoot" more={[]} />
          </div>
        ) : null}
        {st && st.x.length ? (
          <div class="assist-plot">
            <AssistChart series={st} label={() => "step settling"} yLabel="settling" xLabel="kv [1/s]"
              levels={[{ label: "target", value: stMax }]} testid="loop-gain-settling" more={[]} />
          </div>
        ) : null}
      </div>
    </div>
  );
}
