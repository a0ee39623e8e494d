// The acceleration curve of a spindle gear (000 §2.8.4): from 3-4 interpolation points typed
// in (or more, by least squares), or measured by running the spindle up on a copy of the
// machine in that gear. The points and the fitted curves of types 1, 2 and 3 in one chart;
// the chosen type's coefficients proposed as the gear's beschl_kennlinie.
import { useEffect, useState } from "preact/hooks";
import { useGear } from "../ui/useGear";
import type { AssistResult, AssistSeries, AxisStatus, CurveFitRequest, Refusal } from "../api/types";
import { calculate } from "../state/calculators";
import { may } from "../state/control";
import { machineId, online, status } from "../state/session";
import { RefusalLine } from "../ui/useCommand";
import { AssistResultView } from "./AssistResultView";
import { ApplyBar, checkNumber, refusalOf } from "./CalcParts";
import { CurveChart } from "./CurveChart";

type Typ = 1 | 2 | 3;
const TYPES: { typ: Typ; label: string; law: string }[] = [
  { typ: 1, label: "type 1 hyperbola", law: "a = b1 / (1 + b2·ν²·(1 + b3·ν²)), ν = n / n_limit; 3 points" },
  { typ: 2, label: "type 2 polynomial", law: "a = a_konst + b1·Δn + b2·Δn² + b3·Δn³, Δn = n − n_limit; 4 points" },
  { typ: 3, label: "type 3 asynchronous", law: "a_max below N1, a_max·N1/n to N2, a_max·N1·N2/n² above; 3 points" },
];
/** The manual's interpolation points (000 §2.8.4): n in °/s, a in °/s². */
const MANUAL: [string, string][] = [
  ["12000", "16000"],
  ["24000", "8000"],
  ["36000", "4000"],
  ["48000", "2000"],
];

interface Fit {
  result: AssistResult; // the chosen type's: figures and the proposal
  points: AssistSeries;
  curves: AssistSeries[]; // the fits of every type that fits the points
  refused: string[]; // types that do not fit them, and why
}

/** The fitted curve of each type through `pts`, the chosen one's full answer. */
async function fitAll(base: Omit<CurveFitRequest, "typ">, chosen: Typ, first?: AssistResult): Promise<Fit> {
  const answers = await Promise.all(
    TYPES.map(({ typ }) =>
      typ === chosen && first
        ? Promise.resolve<AssistResult | string>(first)
        : calculate("curve-fit", { ...base, typ }).catch((e: unknown) => `type ${typ}: ${refusalOf(e).message}`),
    ),
  );
  const result = answers[chosen - 1];
  if (typeof result === "string") throw new Error(result);
  const curves = answers.flatMap((a, i) => {
    const s = typeof a === "string" ? undefined : a.series.find((x) => x.name === "fit");
    return s ? [{ ...s, name: TYPES[i].label }] : [];
  });
  const points = result.series.find((x) => x.name === "points") as AssistSeries;
  return { result, points, curves, refused: answers.filter((a): a is string => typeof a === "string") };
}

export function CurveFitPanel() {
  const spindles = (status.value?.axes ?? []).filter((a) => a.kind === "spindle");
  const [name, setName] = useState("");
  const sp: AxisStatus | undefined = spindles.find((a) => a.name === name) ?? spindles[0];
  const [typ, setTyp] = useState<Typ>(2);
  const [source, setSource] = useState<"points" | "run-up">("points");
  const [rows, setRows] = useState<[string, string][]>(MANUAL);
  const [nLimit, setNLimit] = useState("");
  const [topRpm, setTopRpm] = useState("");
  const [fit, setFit] = useState<Fit | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const [gear, setGear] = useGear(sp);
  useEffect(() => {
    setFit(null);
    setRefusal(null);
  }, [machineId.value, sp?.name, gear, typ, source]);

  const checks = rows.map(([n, a], i) => [
    checkNumber(n, `n of point ${i + 1}`, 0, 1e7, "°/s"),
    checkNumber(a, `a of point ${i + 1}`, 0, 1e9, "°/s²", true),
  ]);
  const limit = nLimit.trim() === "" ? null : checkNumber(nLimit, "n_limit", 0, 1e7, "°/s", true);
  const top = topRpm.trim() === "" ? null : checkNumber(topRpm, "top speed", 0, 1e5, "rpm", true);
  const errors = [...(source === "points" ? checks.flat() : []), limit, source === "run-up" ? top : null].filter(
    (v): v is string => typeof v === "string",
  );
  const tooFew = source === "points" && rows.length < 3 ? "at least 3 points are needed" : "";

  async function run() {
    if (!sp || errors.length || tooFew) return;
    setBusy(true);
    setRefusal(null);
    try {
      const n_limit_deg_s = typeof limit === "number" ? limit : null;
      if (source === "points") {
        const points = checks.map(([n, a]) => ({ n_deg_s: n as number, a_deg_s2: a as number }));
        setFit(await fitAll({ axis: sp.name, gear, points, n_limit_deg_s, a_min: 0 }, typ));
      } else {
        const measured = await calculate("curve-run-up", { axis: sp.name, gear, typ, n_limit_deg_s, speed_rpm: typeof top === "number" ? top : null });
        const pts = measured.series.find((x) => x.name === "points") as AssistSeries;
        const points = pts.x.map((n, i) => ({ n_deg_s: n, a_deg_s2: pts.y[i] }));
        setFit(await fitAll({ axis: sp.name, gear, points, n_limit_deg_s, a_min: 0 }, typ, measured));
      }
    } catch (e) {
      setFit(null);
      setRefusal(refusalOf(e));
    } finally {
      setBusy(false);
    }
  }

  const setRow = (i: number, j: 0 | 1, v: string) => setRows(rows.map((r, k) => (k === i ? ((j ? [r[0], v] : [v, r[1]]) as [string, string]) : r)));
  const law = TYPES[typ - 1].law;
  return (
    <div class="assist" data-testid="calc-curve-fit">
      <div class="assist-setup">
        <div class="row">
          <label class="assist-field">
            <span>Spindle</span>
            <select data-testid="curve-spindle" value={sp?.name} onChange={(e) => setName((e.target as HTMLSelectElement).value)}>
              {spindles.map((a) => (
                <option key={a.name} value={a.name}>
                  {a.name}
                </option>
              ))}
            </select>
          </label>
          <label class="assist-field">
            <span>Gear</span>
            <select data-testid="curve-gear" value={String(gear)} onChange={(e) => setGear(Number((e.target as HTMLSelectElement).value))}>
              {[1, 2, 3, 4, 5, 6].map((g) => (
                <option key={g} value={g}>
                  M{39 + g} · getriebe[{g - 1}]
                </option>
              ))}
            </select>
          </label>
        </div>
        <fieldset class="assist-choice">
          <legend>Curve type to propose (beschl_kennlinie.typ)</legend>
          {TYPES.map((t) => (
            <label key={t.typ}>
              <input type="radio" name="curve-typ" data-testid={`curve-typ-${t.typ}`} checked={t.typ === typ} onChange={() => setTyp(t.typ)} />
              {t.label}
            </label>
          ))}
        </fieldset>
        <p class="assist-what" data-testid="curve-law">
          {law} <span class="hint">(000 §2.8.4; speeds n in °/s, 1 rpm = 6 °/s)</span>
        </p>
        <fieldset class="assist-choice">
          <legend>Points</legend>
          <label>
            <input type="radio" name="curve-source" data-testid="curve-source-points" checked={source === "points"} onChange={() => setSource("points")} />
            typed: interpolation points (measured on the drive)
          </label>
          <label>
            <input type="radio" name="curve-source" data-testid="curve-source-run-up" checked={source === "run-up"} onChange={() => setSource("run-up")} />
            measured: run the spindle up on a copy of the machine
          </label>
        </fieldset>
        {source === "points" ? (
          <>
            <table class="meas-table curve-points" data-testid="curve-points">
              <thead>
                <tr>
                  <th>#</th>
                  <th>n [°/s]</th>
                  <th>a [°/s²]</th>
                  <th class="num">rpm</th>
                  <th />
                </tr>
              </thead>
              <tbody>
                {rows.map(([n, a], i) => (
                  <tr key={i}>
                    <td>P{i + 1}</td>
                    <td>
                      <input size={8} data-testid={`curve-n-${i}`} value={n} aria-invalid={typeof checks[i][0] === "string"}
                        title={typeof checks[i][0] === "string" ? (checks[i][0] as string) : ""} onInput={(e) => setRow(i, 0, (e.target as HTMLInputElement).value)} />
                    </td>
                    <td>
                      <input size={8} data-testid={`curve-a-${i}`} value={a} aria-invalid={typeof checks[i][1] === "string"}
                        title={typeof checks[i][1] === "string" ? (checks[i][1] as string) : ""} onInput={(e) => setRow(i, 1, (e.target as HTMLInputElement).value)} />
                    </td>
                    <td class="num hint">{typeof checks[i][0] === "number" ? Math.round((checks[i][0] as number) / 6) : ""}</td>
                    <td>
                      <button type="button" class="link" aria-label={`remove point ${i + 1}`} disabled={rows.length <= 3} onClick={() => setRows(rows.filter((_r, k) => k !== i))}>
                        ×
                      </button>
                    </td>
                  </tr>
                ))}
              </tbody>
            </table>
            <div class="row">
              <button type="button" class="secondary" data-testid="curve-add" disabled={rows.length >= 40} onClick={() => setRows([...rows, ["", ""]])}>
                + point
              </button>
              <button type="button" class="secondary" data-testid="curve-manual" onClick={() => setRows(MANUAL)}>
                the manual's points
              </button>
            </div>
            <p class="hint">P1 is (n_limit, a_konst) as the manual defines it; 4 points interpolate the polynomial, 3 the hyperbola, more are fitted by least squares.</p>
          </>
        ) : (
          <label class="assist-field">
            <span>Run up to (empty: the gear's vb_max)</span>
            <span class="row">
              <input data-testid="curve-top" size={8} value={topRpm} aria-invalid={typeof top === "string"} onInput={(e) => setTopRpm((e.target as HTMLInputElement).value)} />
              <span>rpm</span>
            </span>
          </label>
        )}
        <label class="assist-field">
          <span>Limit speed n_limit (empty: P1, or searched)</span>
          <span class="row">
            <input data-testid="curve-n-limit" size={8} value={nLimit} aria-invalid={typeof limit === "string"} onInput={(e) => setNLimit((e.target as HTMLInputElement).value)} />
            <span>°/s</span>
          </span>
        </label>
        {[...errors, tooFew].filter(Boolean).map((e) => (
          <span key={e} class="inline-error" role="alert" data-testid="curve-input-error">
            {e}
          </span>
        ))}
        {source === "run-up" && sp ? (
          <p class="assist-what" data-testid="curve-what">
            {sp.name} runs up with M3 in gear {gear} (M{39 + gear}) to {typeof top === "number" ? `${top} rpm` : "the gear's vb_max"} at the acceleration its
            parameters allow, on a copy of the machine in simulated time; the live spindle does not turn. a(n) is derived from the recorded actual speed.
          </p>
        ) : null}
        <div class="row">
          <button type="button" data-testid="curve-run" disabled={!online.value || !sp || busy || errors.length > 0 || !!tooFew || !may("assist")} onClick={() => void run()}>
            {busy ? "Working…" : source === "points" ? "Fit" : "Run up and fit"}
          </button>
          {busy ? (
            <span class="assist-busy" role="status">
              <span class="spinner" aria-hidden="true" /> {source === "run-up" ? "running up on a copy of the machine…" : "fitting…"}
            </span>
          ) : null}
        </div>
        <RefusalLine refusal={refusal} id="curve-refusal" />
      </div>
      <div class="assist-out">
        {fit ? (
          <>
            <div class="assist-plot">
              <CurveChart points={fit.points} curves={fit.curves} testid="curve-chart" />
            </div>
            {fit.refused.length ? (
              <ul class="assist-notes" data-testid="curve-refused">
                {fit.refused.map((r) => (
                  <li key={r}>{r}</li>
                ))}
              </ul>
            ) : null}
            <AssistResultView result={fit.result} spindle />
            <ApplyBar assistant={fit.result.assistant} changes={fit.result.changes} testid="curve" />
          </>
        ) : (
          <p class="hint assist-empty">Type or measure the points, Fit: the curves of the three types and the chosen one's coefficients follow.</p>
        )}
      </div>
    </div>
  );
}
