// The loop gain sweep's setup in the guided panel: its inputs checked as typed (the limits of
// api/assist.py LoopGainRequest) and what it will move, and for how long, said beforehand.
import { useEffect, useState } from "preact/hooks";
import type { AxisStatus, LoopGainRequest } from "../api/types";
import { numbers, paramsVersion } from "../state/params";
import { machineId } from "../state/session";
import { AssistField } from "./AssistField";
import { perSecond, rawVelocityPerMin } from "../ui/units";

// as nc_sim/assist/loop_gain.py: the default sweep, step, ramp feed and recording lengths
const SWEEP_FACTORS = [0.5, 0.75, 1, 1.5, 2, 2.5, 3];
const MAX_KVS = 12;
const STEP_WINDOWS = 20;
const FEED_SHARE = 0.05;
const SETTLE_TAUS = 10;
const RAMP_WINDOW_S = 0.5;
const RAMP_MARGIN_S = 2;

export interface LoopGainInputs {
  kvs: string; // "10, 20, 40" in 1/s; "": the default sweep
  overshoot: string; // %
  settle: string; // ms
}

export const LOOP_GAIN_START: LoopGainInputs = { kvs: "", overshoot: "5", settle: "200" };

/** The axis' kv, exact-stop window and rapid speed now (engineering units), for the plan. */
export interface AxisNow {
  kv: number; // 1/s
  window: number; // mm | °
  rapidPerMin: number; // mm/min | °/min
}

export function useAxisNow(ax: AxisStatus | undefined): AxisNow | null {
  const [now, setNow] = useState<AxisNow | null>(null);
  useEffect(() => {
    if (!ax || !machineId.value) return;
    const g = Math.max(0, (ax.gear ?? 1) - 1);
    numbers("axis", ax.name).then(
      (m) =>
        setNow({
          kv: (m.get(`getriebe[${g}].kv`) ?? NaN) / 100, // 0.01/s
          window: (m.get("kenngr.exact_stop_window") ?? NaN) * 1e-4, // 0.1 µm | 0.0001°
          rapidPerMin: rawVelocityPerMin(m.get(`getriebe[${g}].vb_eilgang`) ?? NaN),
        }),
      () => setNow(null),
    );
  }, [machineId.value, ax?.name, paramsVersion.value]);
  return now;
}

/** Per input: its value, or why not (kvs: null is the default sweep). */
export function checkLoopGain(inp: LoopGainInputs) {
  const num = (text: string, what: string, lo: number, hi: number, unit: string, loOpen: boolean): number | string => {
    const v = Number(text.trim());
    if (text.trim() === "" || !Number.isFinite(v)) return `${what}: a number is needed`;
    if ((loOpen ? v <= lo : v < lo) || v > hi) return `${what}: ${loOpen ? `> ${lo}` : `≥ ${lo}`} and ≤ ${hi} ${unit}`;
    return v;
  };
  let kvs: number[] | null | string = null;
  if (inp.kvs.trim() !== "") {
    const parts = inp.kvs.split(/[,\s;]+/).filter((p) => p !== "").map(Number);
    if (parts.some((v) => !Number.isFinite(v) || v <= 0 || v > 10000)) kvs = "kv values: numbers > 0 and ≤ 10000 1/s, separated by commas";
    else if (parts.length > MAX_KVS) kvs = `kv values: at most ${MAX_KVS}`;
    else kvs = parts;
  }
  return {
    kvs,
    overshoot: num(inp.overshoot, "overshoot", 0, 100, "%", false),
    settle: num(inp.settle, "settling", 0, 10000, "ms", true),
  };
}

export function loopGainErrors(v: ReturnType<typeof checkLoopGain>): string[] {
  return [v.kvs, v.overshoot, v.settle].filter((x): x is string => typeof x === "string");
}

export function loopGainRequest(axis: string, v: ReturnType<typeof checkLoopGain>): LoopGainRequest {
  return {
    axis,
    kvs: Array.isArray(v.kvs) ? v.kvs : null,
    overshoot_pct: v.overshoot as number,
    settle_ms: v.settle as number,
    direction: 1,
  };
}

const n3 = (v: number) => String(+v.toPrecision(3));

/** What the sweep will do: the kv it tries, the step and the ramp, how long and how far. */
export function describeLoopGain(ax: AxisStatus, v: ReturnType<typeof checkLoopGain>, now: AxisNow | null): string {
  const unit = ax.unit;
  const kvs = Array.isArray(v.kvs) ? [...v.kvs].sort((a, b) => a - b) : now && now.kv > 0 ? SWEEP_FACTORS.map((f) => +(now.kv * f).toFixed(2)) : null;
  const which = kvs ? `kv = ${kvs.map(n3).join(", ")} /s` : "0.5× to 3× the axis' kv";
  const step = now && now.window > 0 ? `${n3(STEP_WINDOWS * now.window)} ${unit}` : `${STEP_WINDOWS} exact-stop windows`;
  const feed = now && now.rapidPerMin > 0 ? +(FEED_SHARE * now.rapidPerMin).toPrecision(2) : null;
  let plan = "";
  if (kvs && feed !== null) {
    const settle = SETTLE_TAUS / kvs[0];
    const travel = perSecond(feed) * (settle + RAMP_WINDOW_S + RAMP_MARGIN_S);
    const total = kvs.length * (2 * settle + RAMP_WINDOW_S + 0.2);
    plan = ` Each ramp commands +${n3(travel)} ${unit} and is recorded for about ${n3(settle + RAMP_WINDOW_S + 0.1)} s; all runs together take about ${n3(total)} s of simulated time.`;
  }
  return (
    `For each of ${which}, on a fresh copy of the machine in simulated time (the live machine does not move): ` +
    `${ax.name} makes a G00 step of +${step} and, on another copy, a G01 ramp at ${feed !== null ? `${n3(feed)} ${unit}/min` : "5 % of its rapid speed"}.` +
    `${plan} Overshoot past the target and settling into the exact-stop window after the command ends are measured on the step, ` +
    "the steady lag (v/kv) on the ramp; the highest kv meeting the target is proposed as getriebe[g].kv (004 §3.6)."
  );
}

/** The sweep's inputs, each with its error beside it as typed. */
export function LoopGainFields(props: {
  inp: LoopGainInputs;
  set: (inp: LoopGainInputs) => void;
  values: ReturnType<typeof checkLoopGain>;
  busy: boolean;
}) {
  const { inp, values } = props;
  const one = (key: keyof LoopGainInputs, label: string, unit: string, testid: string, placeholder = "") => {
    const err = values[key];
    return (
      <AssistField label={label} unit={unit} testid={testid} value={inp[key]} placeholder={placeholder} size={key === "kvs" ? 18 : 8}
        disabled={props.busy} error={typeof err === "string" ? err : null} onInput={(v) => props.set({ ...inp, [key]: v })} />
    );
  };
  return (
    <>
      {one("kvs", "kv values to try", "1/s", "assist-kvs", "0.5× … 3× the axis' kv")}
      {one("overshoot", "Target: step overshoot at most", "%", "assist-overshoot")}
      {one("settle", "Target: settled within", "ms", "assist-settle")}
    </>
  );
}
