// What an assistant answered: the figures with their units and the manual's formula, the
// lag over time, the notes, the verdict (the sign check) or the check f ≈ 1 (multi_gain),
// and the proposed changes before → after.
import type { AssistResult } from "../api/types";
import { figure } from "../state/assist";
import { fmt } from "../ui/format";
import { AssistChart, type Level } from "./AssistChart";
import { AutotuneView } from "./AutotuneView";
import { BodeView } from "./BodeChart";
import { CircleView } from "./CircleChart";
import { LoopGainView } from "./LoopGainResult";
import { RPM_TO_DEG_S, perSecond } from "../ui/units";

/** Names the manual gives the figures, and the decimals they read with. */
const FIGURES: Record<string, { label: string; decimals: number; sig?: number }> = {
  v: { label: "v", decimals: 1 },
  s: { label: "s", decimals: 5 },
  k: { label: "k", decimals: 3 },
  kv: { label: "kv", decimals: 2 },
  f: { label: "f", decimals: 3 },
  multi_gain: { label: "multi_gain now", decimals: 4 },
  multi_gain_new: { label: "multi_gain new", decimals: 4 },
  kv_new: { label: "kv new", decimals: 2 },
  averaged_s: { label: "averaged over", decimals: 3 },
  max_lag: { label: "max lag", decimals: 4 },
  lag_max: { label: "lag_max", decimals: 4 },
  // the calculators (004 §3.4, §3.6.1, 000 §2.2.4) and the acceleration curve (000 §2.8.4)
  resolution: { label: "wegaufz / wegaufn", decimals: 0, sig: 9 },
  distance_per_motor_rev: { label: "distance per motor revolution", decimals: 1 },
  n_motor_rpm: { label: "n (motor)", decimals: 4 },
  v_reso: { label: "v_reso_num / v_reso_denom", decimals: 0, sig: 9 },
  distance_per_time_base: { label: "distance per time base", decimals: 1 },
  n_limit: { label: "n_limit", decimals: 1 },
  a_konst: { label: "a_konst", decimals: 1 },
  b1: { label: "b1", decimals: 0, sig: 9 },
  b2: { label: "b2", decimals: 0, sig: 9 },
  b3: { label: "b3", decimals: 0, sig: 9 },
  a_max: { label: "a_max", decimals: 1 },
  n1: { label: "N1", decimals: 1 },
  n2: { label: "N2", decimals: 1 },
  max_error: { label: "max error", decimals: 0, sig: 3 },
  run_up_s: { label: "run-up time", decimals: 2 },
  "multi-gain-calc.f": { label: "f", decimals: 4 },
  // the frequency response: what the Bode plot marks
  resonance_1_hz: { label: "resonance f_r", decimals: 1, sig: 3 },
  resonance_2_hz: { label: "resonance 2", decimals: 1, sig: 3 },
  resonance_3_hz: { label: "resonance 3", decimals: 1, sig: 3 },
  anti_resonance_1_hz: { label: "anti-resonance f_ar", decimals: 1, sig: 3 },
  anti_resonance_2_hz: { label: "anti-resonance 2", decimals: 1, sig: 3 },
  anti_resonance_3_hz: { label: "anti-resonance 3", decimals: 1, sig: 3 },
  phase_margin_deg: { label: "phase margin", decimals: 1, sig: 3 },
  gain_margin_db: { label: "gain margin", decimals: 1, sig: 3 },
  crossover_hz: { label: "crossover f_c", decimals: 1, sig: 3 },
  phase_crossover_hz: { label: "phase crossover f_180", decimals: 1, sig: 3 },
  bandwidth_hz: { label: "bandwidth (−3 dB)", decimals: 1, sig: 3 },
  peak_db: { label: "peak", decimals: 1, sig: 3 },
  coherence_min: { label: "lowest coherence", decimals: 2, sig: 2 },
  measured_s: { label: "measured for", decimals: 1, sig: 3 },
  rise_ms: { label: "rise time", decimals: 1, sig: 3 },
  rise_ms_expected: { label: "rise time (model)", decimals: 1, sig: 3 },
  overshoot_pct: { label: "overshoot", decimals: 1, sig: 3 },
  overshoot_pct_expected: { label: "overshoot (model)", decimals: 1, sig: 3 },
  settling_ms: { label: "settling time", decimals: 1, sig: 3 },
  settling_ms_expected: { label: "settling time (model)", decimals: 1, sig: 3 },
  rate_hz: { label: "sampling rate", decimals: 0 },
  samples: { label: "samples", decimals: 0 },
  torque_peak_nm: { label: "torque peak", decimals: 2, sig: 3 },
  twist_peak_um: { label: "motor ahead of load, peak", decimals: 2, sig: 3 },
  "multi-gain-calc.multi_gain": { label: "multi_gain", decimals: 4 },
  // the circularity test (ISO 230-4)
  circular_um: { label: "circular deviation G", decimals: 2, sig: 3 },
  bidirectional_um: { label: "bidirectional G(b)", decimals: 2, sig: 3 },
  circular_ccw_um: { label: "G, CCW", decimals: 2, sig: 3 },
  circular_cw_um: { label: "G, CW", decimals: 2, sig: 3 },
  radius_change_ccw_um: { label: "radius change, CCW", decimals: 2, sig: 3 },
  radius_change_cw_um: { label: "radius change, CW", decimals: 2, sig: 3 },
  ellipse_ccw_um: { label: "ellipse, CCW", decimals: 2, sig: 3 },
  ellipse_cw_um: { label: "ellipse, CW", decimals: 2, sig: 3 },
  ellipse_ccw_deg: { label: "its axis, CCW", decimals: 0, sig: 3 },
  ellipse_cw_deg: { label: "its axis, CW", decimals: 0, sig: 3 },
  spike_ccw_um: { label: "reversal spike, CCW", decimals: 2, sig: 3 },
  spike_cw_um: { label: "reversal spike, CW", decimals: 2, sig: 3 },
  spike_ccw_deg: { label: "at, CCW", decimals: 0, sig: 3 },
  spike_cw_deg: { label: "at, CW", decimals: 0, sig: 3 },
  kv_mismatch_ms: { label: "1/kv difference", decimals: 3, sig: 3 },
  // the speed-loop autotune
  kp: { label: "Kp (p1460)", decimals: 4, sig: 4 },
  tn_ms: { label: "Tn (p1462)", decimals: 2, sig: 4 },
  pm_deg: { label: "phase margin, predicted", decimals: 1, sig: 3 },
  gm_db: { label: "gain margin, predicted", decimals: 1, sig: 3 },
  pm_now_deg: { label: "phase margin, as it is", decimals: 1, sig: 3 },
  bandwidth_now_hz: { label: "bandwidth, as it is", decimals: 1, sig: 3 },
  pm_achieved_deg: { label: "phase margin, measured", decimals: 1, sig: 3 },
  gm_achieved_db: { label: "gain margin, measured", decimals: 1, sig: 3 },
  bandwidth_achieved_hz: { label: "bandwidth, measured", decimals: 1, sig: 3 },
  target_pm_deg: { label: "phase margin, template", decimals: 0, sig: 3 },
  target_gm_db: { label: "gain margin, template", decimals: 0, sig: 3 },
  notch_hz: { label: "notch", decimals: 1, sig: 4 },
  resonance_hz: { label: "resonance f_r", decimals: 1, sig: 4 },
  crossover_db_measured: { label: "|L| at f_c, measured", decimals: 2, sig: 3 },
  crossover_deg_measured: { label: "phase at f_c, measured", decimals: 1, sig: 4 },
  prediction_error_db: { label: "prediction error, |L|", decimals: 2 },
  prediction_error_deg: { label: "prediction error, phase", decimals: 1 },
  gm_now_db: { label: "gain margin, as it is", decimals: 1, sig: 3 },
  kv_max: { label: "kv max (no overshoot)", decimals: 1, sig: 3 },
  lag_1m_min_mm: { label: "lag at 1 m/min", decimals: 4, sig: 3 },
};
const HIDDEN = new Set(["runaway", "observed"]); // the sign check's verdict says them in words

/** A figure with its decimals, or in significant digits where those decimals would lose it
 * (the curve's b3 is of order 1e-10). */
export function figureText(v: number, decimals: number, sig?: number): string {
  if (v === 0 || !Number.isFinite(v) || (!sig && Math.abs(v) >= 10 ** (2 - decimals))) return fmt(v, decimals);
  const digits = sig ?? 9;
  const text = Math.abs(v) < 1e-3 || Math.abs(v) >= 1e7 ? v.toExponential(digits - 1) : v.toPrecision(digits);
  return text.replace(/-/g, "−");
}

/** |f − 1| within this: k equals kv (004 §3.6.2 equation 1), nothing left to correct. */
export const F_TOLERANCE = 0.01;

/** f of the multi_gain experiment (k against kv); the calculator's f is another figure. */
const checkFactor = (r: AssistResult): number | null => (r.assistant === "multi-gain" ? figure(r, "f") : null);

/** A figure's name and decimals: the assistant's own first (the calculator's f and multi_gain
 * are not the experiment's). */
const figureSpec = (r: AssistResult, name: string) => FIGURES[`${r.assistant}.${name}`] ?? FIGURES[name] ?? perAxis(name);

/** Figures named after an axis (the circle's kv_Z, lost_motion_X_um). */
function perAxis(name: string): { label: string; decimals: number; sig?: number } | undefined {
  const lost = /^lost_motion_(\w+)_um$/.exec(name);
  if (lost) return { label: `lost motion ${lost[1]}`, decimals: 2, sig: 3 };
  const kv = /^kv_([A-Z]\w*)$/.exec(name);
  return kv ? { label: `kv ${kv[1]} (effective)`, decimals: 2, sig: 4 } : undefined;
}

/** The multi_gain run found k = kv already (f within 1 %: it proposes nothing then). */
export const settled = (r: AssistResult): boolean => {
  const f = checkFactor(r);
  return f !== null && Math.abs(f - 1) <= F_TOLERANCE;
};

/** The sign check's verdict, from the parameters it proposes to flip. */
export function signVerdict(r: AssistResult): string {
  const flips = r.changes.map((c) => c.parameter.replace(/^lr_hw\[\d+\]\./, ""));
  if (!r.ok) return "no verdict: lag monitoring tripped first (see the notes)";
  if (!flips.length) return "signs right";
  return flips.length === 2 ? "flip both vz_stellgr and vz_istw" : `flip ${flips[0]}`;
}

/** The lag kv alone would give (v/kv) and the measured mean, as levels on the lag chart. */
function levels(r: AssistResult, spindle: boolean): Level[] {
  const v = figure(r, "v");
  const kv = figure(r, "kv");
  const s = figure(r, "s");
  if (v === null || kv === null || s === null) return [];
  const perS = spindle ? v * RPM_TO_DEG_S : perSecond(v); // rpm -> °/s; mm/min (°/min) -> per s
  const sign = Math.sign(s) || 1;
  return [
    { label: "v/kv (expected)", value: (sign * perS) / kv },
    { label: "s (measured mean)", value: s },
  ];
}

export function AssistResultView(props: { result: AssistResult; spindle: boolean; live?: boolean }) {
  const r = props.result;
  const f = checkFactor(r);
  const lag = r.series.find((s) => s.name === "lag");
  const shown = r.figures.filter((x) => !HIDDEN.has(x.name));
  return (
    <div class="assist-result" data-testid="assist-result">
      {r.assistant === "sign-check" ? <SignVerdict result={r} /> : null}
      {r.assistant === "frequency-response" ? <BodeView result={r} /> : null}
      {r.assistant === "drive-trace" ? <DriveTraceCharts result={r} /> : null}
      {r.assistant === "circle" ? <CircleView result={r} /> : null}
      {r.assistant === "autotune" ? <AutotuneView result={r} /> : null}
      {r.assistant === "step-response" && r.series.length === 2 ? (
        <div class="assist-plot">
          <AssistChart series={r.series[0]} more={[r.series[1]]} levels={[]} testid="step-chart"
            label={(s) => s.name} xLabel={`time after the step [${r.series[0].x_unit}]`} yLabel={r.series[0].name} />
        </div>
      ) : null}
      {f !== null ? (
        settled(r) ? (
          <p class="assist-check ok" data-testid="assist-check" data-ok="1">
            ✓ f = {fmt(f, 3)} ≈ 1: k equals kv, multi_gain matches the drive (004 §3.6.2 equation 1)
          </p>
        ) : (
          <p class="assist-check off" data-testid="assist-check" data-ok="0">
            f = {fmt(f, 3)}: k is {f > 1 ? "lower" : "higher"} than kv — apply the proposal, then run again
          </p>
        )
      ) : null}
      {r.assistant === "loop-gain" ? <LoopGainView result={r} /> : (
      <div class="assist-figures">
        <table class="meas-table" data-testid="assist-figures">
          <thead>
            <tr>
              <th>Figure</th>
              <th class="num">Value</th>
              <th>Unit</th>
              <th>What it is</th>
            </tr>
          </thead>
          <tbody>
            {shown.map((x) => (
              <tr key={x.name} data-testid={`assist-fig-row-${x.name}`}>
                <td class="mono">{figureSpec(r, x.name)?.label ?? x.name}</td>
                <td class="num" data-testid={`assist-fig-${x.name}`}>
                  {figureText(x.value, figureSpec(r, x.name)?.decimals ?? 4, figureSpec(r, x.name)?.sig)}
                </td>
                <td>{x.unit}</td>
                <td class="hint">{x.text}</td>
              </tr>
            ))}
          </tbody>
        </table>
        {lag ? (
          <div class="assist-plot">
            <AssistChart series={lag} levels={levels(r, props.spindle)} testid="assist-chart"
              xLabel={`time on ${props.live ? "the machine" : "the copy"} [${lag.x_unit || "s"}]`} />
          </div>
        ) : null}
      </div>
      )}
      {r.notes.length ? (
        <ul class="assist-notes" data-testid="assist-notes">
          {r.notes.map((n) => (
            <li key={n} class={/^f = .*> 1|tripped|job error|ran away|^no kv/.test(n) ? "warn" : ""}>
              {n}
            </li>
          ))}
        </ul>
      ) : null}
      {r.changes.length ? (
        <table class="meas-table assist-changes" data-testid="assist-changes">
          <caption>
            Proposed parameter changes (list units)
          </caption>
          <thead>
            <tr>
              <th>List</th>
              <th>Parameter</th>
              <th class="num">Before</th>
              <th />
              <th class="num">After</th>
              <th>Why</th>
            </tr>
          </thead>
          <tbody>
            {r.changes.map((c) => (
              <tr key={c.parameter} data-testid={`assist-change-${c.parameter}`}>
                <td>{c.target}</td>
                <td class="mono">{c.parameter}</td>
                <td class="num">{String(c.before)}</td>
                <td>→</td>
                <td class="num">
                  <b>{String(c.after)}</b>
                </td>
                <td class="hint">{c.why}</td>
              </tr>
            ))}
          </tbody>
        </table>
      ) : (
        <p class="hint" data-testid="assist-no-changes">
          No parameter change proposed.
        </p>
      )}
    </div>
  );
}

/** The drive's signals, one chart per unit (speeds, torques, the twist), over time. */
function DriveTraceCharts(props: { result: AssistResult }) {
  const units = [...new Set(props.result.series.map((s) => s.y_unit))];
  return (
    <>
      {units.map((u) => {
        const [first, ...more] = props.result.series.filter((s) => s.y_unit === u);
        return (
          <div class="assist-plot" key={u}>
            <AssistChart series={first} more={more} levels={[]} testid={`drive-trace-${u}`}
              label={(s) => s.name} xLabel="time [s]" yLabel={u === "µm" ? "motor ahead of load" : u === "Nm" ? "torque" : "speed"} />
          </div>
        );
      })}
    </>
  );
}

function SignVerdict(props: { result: AssistResult }) {
  const r = props.result;
  const verdict = signVerdict(r);
  const maxLag = figure(r, "max_lag") ?? 0;
  const limit = figure(r, "lag_max") ?? 0;
  const unit = r.figures.find((x) => x.name === "max_lag")?.unit ?? "";
  const share = limit > 0 ? Math.min(1, maxLag / limit) : 0;
  const good = verdict === "signs right";
  return (
    <div class="sign-verdict">
      <p class={`assist-check ${good ? "ok" : "off"}`} data-testid="assist-verdict">
        {good ? "✓ " : "⚠ "}
        {verdict}
      </p>
      <div class="lag-gauge" title="largest lag during the check against lag monitoring's limit">
        <span>
          max lag <b data-testid="assist-max-lag">{fmt(maxLag, 4)}</b> of lag_max {fmt(limit, 4)} {unit}
        </span>
        <span class="gauge">
          <span class={share > 0.8 ? "fill bad" : "fill"} style={{ width: `${(share * 100).toFixed(1)}%` }} />
        </span>
      </div>
    </div>
  );
}
