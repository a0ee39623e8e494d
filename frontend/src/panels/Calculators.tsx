// The commissioning calculators beside the assistants: the arithmetic of the manuals' worked
// examples (resolution 004 §3.4, multi_gain 004 §3.6.1, speed scaling 000 §2.2.4), the
// acceleration curve (000 §2.8.4) and the gear ranges (000 §2.8.2). Inputs are checked as
// typed (the service checks again); the result shows the figures with the manual's formula
// and the proposed changes before → after, which Apply puts on trial (Keep / Revert).
import { useEffect, useState } from "preact/hooks";
import { useGear } from "../ui/useGear";
import type { AssistResult, AxisStatus, Refusal } from "../api/types";
import type { AssistantInfo } from "../api/types";
import { catalogue, loadCatalogue, runAssistant } from "../state/assist";
import { type CalculatorBodies, calculate } from "../state/calculators";
import { lockedAssistants } from "../state/exercise";
import { may } from "../state/control";
import { machineId, online, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { RefusalLine } from "../ui/useCommand";
import { AssistResultView } from "./AssistResultView";
import { ApplyBar, Field, checkNumber, refusalOf } from "./CalcParts";
import "./calculators.css";
import { CurveFitPanel } from "./CurveFitPanel";
import { GearRanges } from "./GearRanges";
import { codeSpans } from "../ui/codeSpans";
import { SchemaFields, axesFor, formBody, formFields, startTexts } from "./SchemaForm";

// the calculators of the catalogue (GET /api/assistants) with a guided form of their own;
// any other gets the form its request schema describes. The gear-range preview is not an
// assistant (it answers a selection table, not a proposal with figures).
const FORM_TOOLS = new Set<string>(["resolution", "multi-gain-calc", "speed-scaling"]);
const GEAR_RANGES = { name: "gear-ranges", title: "Gear ranges", section: "000 §2.8.2" };

/** The calculators' area of the Commissioning workspace. */
export function Calculators() {
  const [tool, setTool] = useState("resolution");
  const mayAssist = may("assist");
  useEffect(() => void loadCatalogue(), []);
  const calculators = catalogue.value.filter((a) => a.kind === "calculator");
  const TOOLS = [...calculators, GEAR_RANGES];
  const info = calculators.find((a) => a.name === tool);
  return (
    <Panel title="Calculators" id="calc">
      <div class="calc-tools" role="tablist" aria-label="calculator">
        {TOOLS.map((t) => (
          <button type="button" role="tab" key={t.name} aria-selected={t.name === tool} class={t.name === tool ? "active" : ""}
            data-testid={`calc-pick-${t.name}`} onClick={() => setTool(t.name)}>
            {t.title} <span class="hint">({t.section})</span>
            {lockedAssistants.value.includes(t.name) ? <span class="locked" title="your exercise locks it: work it out by hand"> 🔒</span> : null}
          </button>
        ))}
      </div>
      {lockedAssistants.value.includes(tool) ? (
        <p class="assist-readonly" role="status" data-testid="calc-locked">
          🔒 Your exercise locks this calculator: work it out by hand.
        </p>
      ) : null}
      {!mayAssist ? (
        <p class="assist-readonly" role="status" data-testid="calc-readonly">
          Read-only: the calculators need the role operator.
        </p>
      ) : null}
      {lockedAssistants.value.includes(tool) ? null : tool === "curve-fit" ? (
        <CurveFitPanel />
      ) : tool === "gear-ranges" ? (
        <GearRanges />
      ) : FORM_TOOLS.has(tool) ? (
        <FormCalculator key={tool} tool={tool as FormTool} section={info?.section ?? ""} />
      ) : info ? (
        <SchemaCalculator key={tool} info={info} />
      ) : null}
    </Panel>
  );
}

// --- resolution, multi_gain by calculation, speed scaling: a form each ---------------------

type FormTool = "resolution" | "multi-gain-calc" | "speed-scaling";
type Scaling = "full-scale" | "digits" | "sercos-rotary" | "sercos-linear";

interface Inputs {
  increments: string;
  pitch: string;
  ratio: string;
  scaling: Scaling;
  fsDigits: string;
  fsRpm: string;
  digitsPerRpm: string;
  weightRpm: string;
  weightMMin: string;
  rpm: string;
  timeBase: "0" | "1" | "2";
  cycleMs: string;
}

const START: Inputs = {
  increments: "4096", pitch: "5", ratio: "1", scaling: "full-scale", fsDigits: "32767", fsRpm: "9000",
  digitsPerRpm: "139.81", weightRpm: "0.0001", weightMMin: "0.0001", rpm: "3000", timeBase: "0", cycleMs: "",
};

/** The manual's worked example of each calculator (with what it gives), to try or compare. */
const EXAMPLES: Record<FormTool, { text: string; inputs: Partial<Inputs>; axisKind: "linear" | "rotary" }> = {
  resolution: { text: "4096 increments per revolution, 5 mm pitch → 4096/50000 (with i = 10: 4096/5000)", inputs: { increments: "4096", pitch: "5", ratio: "1" }, axisKind: "linear" },
  "multi-gain-calc": { text: "terminal spindle: 32767 digits at 10 V = 9000 rpm → 10.1134 (with i = 5: 50.5668)", inputs: { scaling: "full-scale", fsDigits: "32767", fsRpm: "9000", ratio: "1" }, axisKind: "rotary" },
  "speed-scaling": { text: "32767 increments for 3000 rpm, per minute → 32767/1080000000", inputs: { increments: "32767", rpm: "3000", timeBase: "0", ratio: "1" }, axisKind: "rotary" },
};

const FORMULAS: Record<FormTool, string> = {
  resolution:
    "wegaufz / wegaufn = encoder increments per motor revolution ÷ distance per motor revolution: pitch / i in 0.1 µm (linear), 360° / i in 0.0001° (rotary).",
  "multi-gain-calc":
    "multi_gain = f · n: f the command value per motor rpm (the drive's scaling), n the motor speed for 1 m/min (linear: 1000 mm/min ÷ pitch · i) or 1000 °/min (rotary: 1000/360 · i).",
  "speed-scaling":
    "v_reso_num / v_reso_denom = increments ÷ distance the spindle covers at that speed in the time base, in 0.001° (speed / i · 360000 per minute).",
};

function formChecks(tool: FormTool, inp: Inputs, rotary: boolean) {
  const ratio = checkNumber(inp.ratio, "gear ratio i", 0, 1e6, "", true);
  const pitch = rotary ? null : checkNumber(inp.pitch, "pitch", 0, 1e4, "mm", true);
  if (tool === "resolution")
    return { increments: checkNumber(inp.increments, "increments", 0, 4294967295, "", true, true), pitch, ratio };
  if (tool === "speed-scaling")
    return {
      increments: checkNumber(inp.increments, "increments", 0, 4294967295, "", true, true),
      rpm: checkNumber(inp.rpm, "speed", 0, 1e6, "rpm", true),
      cycleMs: inp.timeBase === "2" && inp.cycleMs.trim() !== "" ? checkNumber(inp.cycleMs, "cycle time", 0, 1000, "ms", true) : null,
      ratio,
    };
  const s = inp.scaling;
  return {
    fsDigits: s === "full-scale" ? checkNumber(inp.fsDigits, "full-scale value", 0, 2147483647, "digits", true, true) : null,
    fsRpm: s === "full-scale" ? checkNumber(inp.fsRpm, "full-scale speed", 0, 1e6, "rpm", true) : null,
    digitsPerRpm: s === "digits" ? checkNumber(inp.digitsPerRpm, "digits per rpm", 0, 1e9, "", true) : null,
    weightRpm: s === "sercos-rotary" ? checkNumber(inp.weightRpm, "weighting", 0, 1000, "rpm", true) : null,
    weightMMin: s === "sercos-linear" ? checkNumber(inp.weightMMin, "weighting", 0, 1000, "m/min", true) : null,
    pitch,
    ratio,
  };
}

const num = (v: number | string | null | undefined): number | null => (typeof v === "number" ? v : null);

function FormCalculator(props: { tool: FormTool; section: string }) {
  const { tool } = props;
  const all = status.value?.axes ?? [];
  const axes = tool === "speed-scaling" ? all.filter((a) => a.kind === "spindle") : all;
  const [axisName, setAxisName] = useState("");
  const ax: AxisStatus | undefined = axes.find((a) => a.name === axisName) ?? axes[0];
  const [gear, setGear] = useGear(ax);
  const [inp, setInp] = useState<Inputs>(START);
  const [result, setResult] = useState<AssistResult | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const rotary = ax?.kind !== "linear";
  const checks = formChecks(tool, inp, rotary);
  const errors = Object.values(checks).filter((v): v is string => typeof v === "string");
  const set = (patch: Partial<Inputs>) => setInp({ ...inp, ...patch });
  useEffect(() => {
    setResult(null);
    setRefusal(null);
  }, [machineId.value, ax?.name, gear]);

  function body(): CalculatorBodies[FormTool] {
    const c = checks as unknown as Record<string, number | string | null>;
    const axis = ax?.name ?? "";
    const gear_ratio = num(c.ratio) ?? 1;
    if (tool === "resolution")
      return { axis, gear, increments_per_rev: num(c.increments) ?? 0, pitch_mm: num(c.pitch), rotary, gear_ratio };
    if (tool === "speed-scaling")
      return { axis, increments: num(c.increments) ?? 0, speed_rpm: num(c.rpm) ?? 0, time_base: Number(inp.timeBase) as 0 | 1 | 2, cycle_ms: num(c.cycleMs), gear_ratio };
    return {
      axis, gear, gear_ratio, pitch_mm: num(c.pitch), full_scale_digits: num(c.fsDigits), full_scale_rpm: num(c.fsRpm),
      digits_per_rpm: num(c.digitsPerRpm), speed_weighting_rpm: num(c.weightRpm), speed_weighting_m_per_min: num(c.weightMMin),
    };
  }

  async function run() {
    if (!ax || errors.length) return;
    setBusy(true);
    setRefusal(null);
    try {
      setResult(await calculate(tool, body() as never));
    } catch (e) {
      setRefusal(refusalOf(e));
      setResult(null);
    } finally {
      setBusy(false);
    }
  }

  const c = checks as unknown as Record<string, number | string | null>;
  const field = (key: keyof Inputs, label: string, unit: string) =>
    c[key] === null || c[key] === undefined ? null : (
      <Field label={label} unit={unit} value={inp[key] as string} check={c[key] as number | string} testid={`calc-${key}`}
        onInput={(v) => set({ [key]: v })} />
    );
  const ex = EXAMPLES[tool];
  return (
    <div class="assist" data-testid={`calc-${tool}`}>
      <div class="assist-setup">
        <label class="assist-field">
          <span>{tool === "speed-scaling" ? "Spindle" : "Axis"}</span>
          <select data-testid="calc-axis" value={ax?.name} onChange={(e) => setAxisName((e.target as HTMLSelectElement).value)}>
            {axes.map((a) => (
              <option key={a.name} value={a.name}>
                {a.name} ({a.kind})
              </option>
            ))}
          </select>
        </label>
        {tool !== "speed-scaling" ? (
          <label class="assist-field">
            <span>Gear record</span>
            <select data-testid="calc-gear" value={String(gear)} onChange={(e) => setGear(Number((e.target as HTMLSelectElement).value))}>
              {[1, 2, 3, 4, 5, 6].map((g) => (
                <option key={g} value={g}>
                  getriebe[{g - 1}] (gear {g}{ax?.kind === "spindle" ? `, M${39 + g}` : ""})
                </option>
              ))}
            </select>
          </label>
        ) : null}
        {tool === "resolution" ? field("increments", "Encoder increments per motor revolution", "incr") : null}
        {tool === "multi-gain-calc" ? (
          <>
            <label class="assist-field">
              <span>Drive scaling</span>
              <select data-testid="calc-scaling" value={inp.scaling} onChange={(e) => set({ scaling: (e.target as HTMLSelectElement).value as Scaling })}>
                <option value="full-scale">D/A full scale (terminal, ±10 V)</option>
                <option value="digits">digits per rpm (Lightbus)</option>
                <option value="sercos-rotary">SERCOS rotary weighting</option>
                <option value="sercos-linear">SERCOS translatory weighting</option>
              </select>
            </label>
            {field("fsDigits", "Command value at full scale", "digits")}
            {field("fsRpm", "Motor speed at full scale", "rpm")}
            {field("digitsPerRpm", "Command value per motor rpm", "digits/rpm")}
            {field("weightRpm", "Speed weighting", "rpm per digit")}
            {field("weightMMin", "Speed weighting", "m/min per digit")}
          </>
        ) : null}
        {tool === "speed-scaling" ? (
          <>
            {field("increments", "Value output to the drive", "incr")}
            {field("rpm", "Motor speed at that value", "rpm")}
            <label class="assist-field">
              <span>Time base (antr.v_time_base)</span>
              <select data-testid="calc-time-base" value={inp.timeBase} onChange={(e) => set({ timeBase: (e.target as HTMLSelectElement).value as Inputs["timeBase"] })}>
                <option value="0">0 per minute</option>
                <option value="1">1 per second</option>
                <option value="2">2 per cycle</option>
              </select>
            </label>
            {inp.timeBase === "2" ? (
              <Field label="Cycle time (empty: the machine's)" unit="ms" value={inp.cycleMs} check={c.cycleMs ?? 0} testid="calc-cycleMs"
                onInput={(v) => set({ cycleMs: v })} />
            ) : null}
          </>
        ) : null}
        {tool !== "speed-scaling" ? (rotary ? <p class="hint">Rotary: 360° per output revolution.</p> : field("pitch", "Spindle pitch (per output revolution)", "mm")) : null}
        {field("ratio", "Gear ratio i (motor revolutions per output revolution)", "")}
        <p class="assist-what" data-testid="calc-formula">
          {FORMULAS[tool]} <span class="hint">({props.section})</span>
        </p>
        <p class="hint calc-example">
          Manual's example: {ex.text}{" "}
          <button type="button" class="link" data-testid="calc-example" onClick={() => {
            setInp({ ...inp, ...ex.inputs });
            const want = axes.find((a) => (ex.axisKind === "linear" ? a.kind === "linear" : a.kind !== "linear"));
            if (want) setAxisName(want.name);
          }}>
            use it
          </button>
        </p>
        <div class="row">
          <button type="button" data-testid="calc-run" disabled={!online.value || !ax || busy || errors.length > 0 || !may("assist")} onClick={() => void run()}>
            Calculate
          </button>
        </div>
        <RefusalLine refusal={refusal} id="calc-refusal" />
      </div>
      <div class="assist-out">
        {result && errors.length === 0 ? (
          <>
            <AssistResultView result={result} spindle={ax?.kind === "spindle"} />
            <ApplyBar assistant={tool} changes={result.changes} testid="calc" />
          </>
        ) : (
          <p class="hint assist-empty">Type the inputs, Calculate: the figures and the proposed parameters follow.</p>
        )}
      </div>
    </div>
  );
}

/** A calculator without a guided form: the form its request schema describes. */
function SchemaCalculator(props: { info: AssistantInfo }) {
  const { info } = props;
  const fields = formFields(info.request);
  const axes = axesFor(fields, status.value?.axes ?? []);
  const [axisName, setAxisName] = useState("");
  const ax = axes.find((a) => a.name === axisName) ?? axes[0];
  const [texts, setTexts] = useState(() => startTexts(fields));
  const [result, setResult] = useState<AssistResult | null>(null);
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [busy, setBusy] = useState(false);
  const form = formBody(fields, texts, ax?.name ?? "");
  const bad = Object.keys(form.errors).length > 0;
  useEffect(() => setResult(null), [machineId.value, ax?.name]);

  async function run() {
    setBusy(true);
    setRefusal(null);
    try {
      setResult(await runAssistant(info.name, form.body, "copy"));
    } catch (e) {
      setRefusal(refusalOf(e));
      setResult(null);
    } finally {
      setBusy(false);
    }
  }
  return (
    <div class="assist" data-testid={`calc-${info.name}`}>
      <div class="assist-setup">
        <label class="assist-field">
          <span>Axis</span>
          <select data-testid="calc-axis" value={ax?.name} onChange={(e) => setAxisName((e.target as HTMLSelectElement).value)}>
            {axes.map((a) => (
              <option key={a.name} value={a.name}>
                {a.name} ({a.kind})
              </option>
            ))}
          </select>
        </label>
        <SchemaFields fields={fields} texts={texts} errors={form.errors} disabled={busy} testid="calc-in"
          set={(k, v) => setTexts({ ...texts, [k]: v })} />
        <p class="assist-what" data-testid="calc-formula">
          {codeSpans(info.text)} <span class="hint">({info.section})</span>
        </p>
        <div class="row">
          <button type="button" data-testid="calc-run" disabled={!online.value || !ax || busy || bad || !may("assist")} onClick={() => void run()}>
            Calculate
          </button>
        </div>
        <RefusalLine refusal={refusal} id="calc-refusal" />
      </div>
      <div class="assist-out">
        {result ? (
          <>
            <AssistResultView result={result} spindle={ax?.kind === "spindle"} />
            <ApplyBar assistant={info.name} changes={result.changes} testid="calc" />
          </>
        ) : (
          <p class="hint assist-empty">Type the inputs, Calculate: the figures and the proposed parameters follow.</p>
        )}
      </div>
    </div>
  );
}
