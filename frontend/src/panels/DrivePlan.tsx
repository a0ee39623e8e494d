// What a drive measurement will do before it runs: how long the excitation lasts and how far
// the axis travels meanwhile, from the form's values and the axis' drive parameters, and a
// plain word when the axis runs the ideal plant (no drive to measure).
import { useEffect, useState } from "preact/hooks";
import type { AxisStatus } from "../api/types";
import { loadList, paramsVersion } from "../state/params";
import { machineId, status } from "../state/session";
import { fmt } from "../ui/format";

/** The measurement's length in simulated s, as nc_sim/assist/frequency_response.py plans it
 * (`_segment`: a PRBS period of 2^order − 1 samples, or a sweep of 2^order, resolving f_min
 * with four bins; `averages` half-overlapping segments; 0.2 s lead-in). */
export function frfSeconds(fs: number, fMin: number, averages: number, prbs: boolean): number {
  const need = Math.min(1 << 16, Math.max(256, Math.ceil((4 * fs) / fMin)));
  const order = Math.max(8, Math.ceil(Math.log2(need + 1)));
  const nseg = prbs ? 2 ** order - 1 : 2 ** order;
  const count = nseg + (averages - 1) * Math.floor(nseg / 2);
  return (count + Math.round(0.2 * fs)) / fs;
}

interface Drive {
  cascade: boolean | null; // null: the list hides the plant (a class seat's student)
  samplingS: number; // the drive's step
  mmPerRev: number; // travel per motor revolution (mm | °)
}

function useDrive(axis: string): Drive | null {
  const [d, setD] = useState<Drive | null>(null);
  useEffect(() => {
    if (!machineId.value) return;
    loadList("axis", axis).then(
      (list) => {
        const value = new Map(list.map((p) => [p.name, p.value]));
        const plant = value.get("sim.plant");
        const n = (key: string, fallback: number) => (typeof value.get(key) === "number" ? (value.get(key) as number) : fallback);
        setD({
          cascade: plant === undefined ? null : plant === "DRIVE_CASCADE" || plant === 1,
          samplingS: n("drive.sampling_time", 125) * 1e-6,
          mmPerRev: n("sim.mech.travel_per_rev", 100000) * 1e-4,
        });
      },
      () => setD(null),
    );
  }, [machineId.value, axis, paramsVersion.value]);
  return d;
}

const num = (v: unknown, fallback: number): number => (typeof v === "number" && Number.isFinite(v) ? v : fallback);

/** `live`: said in the confirmation of a run on the machine (no word about the copy). */
export function DrivePlan(props: { name: string; axis: AxisStatus; body: Record<string, unknown>; live?: boolean }) {
  const { name, axis, body } = props;
  const drive = useDrive(axis.name);
  const cycle = status.value?.simulation.cycle_s ?? 0.001;
  if (name === "circle") return <CirclePlan body={body} live={props.live} />;
  // a seat's student sees no sim.* list: neither the plant nor its travel per revolution
  if (!drive || drive.cascade === null) return null;
  if (!drive.cascade)
    return (
      <p class="assist-check off" data-testid="drive-plan" data-cascade="0">
        {axis.name} runs the ideal plant (sim.plant IDEAL): there is no drive to measure. Set sim.plant to DRIVE_CASCADE in
        Parameters.
      </p>
    );
  const unit = axis.unit ?? "mm";
  const ts = cycle / Math.max(1, Math.round(cycle / drive.samplingS)); // the drive's step
  let text: string;
  if (name === "frequency-response") {
    const position = num(body.measurement, 1) === 4;
    const fs = position ? 1 / cycle : 1 / ts;
    const seconds = frfSeconds(fs, num(body.f_min_hz, 5), num(body.averages, 10), num(body.excitation, 1) === 1);
    const offset = num(body.offset_rpm, 0);
    const travel = (Math.abs(offset) / 60) * drive.mmPerRev * seconds;
    const window = num(body.window_mm, 50);
    const where = offset > 0 ? "+" : "−";
    if (travel >= window)
      return (
        <p class="assist-check off" data-testid="drive-plan" data-cascade="1" data-fits="0">
          At {fmt(offset, 0)} rpm {axis.name} would travel {fmt(travel, 1)} {unit} in the {fmt(seconds, 1)} s of the
          measurement: more than the position window of ±{window < 1 ? fmt(window, 3) : fmt(window, 0)} {unit}. A wider
          window, a lower offset speed or fewer averages.
        </p>
      );
    text =
      `${axis.name} is excited for ${fmt(seconds, 1)} s of machine time` +
      (offset
        ? `, turning at ${fmt(offset, 0)} rpm: it travels about ${fmt(travel, 1)} ${unit} towards ${where}, then goes back to where it started`
        : ", holding its position") +
      ` (position window ±${window < 1 ? fmt(window, 3) : fmt(window, 0)} ${unit}).`;
  } else if (name === "autotune") {
    const fs = 1 / ts;
    const one = frfSeconds(fs, num(body.f_min_hz, 5), num(body.averages, 6), true);
    const offset = num(body.offset_rpm, 60);
    const travel = (Math.abs(offset) / 60) * drive.mmPerRev * one;
    text =
      `${axis.name} is measured twice (the mechanics, then the open speed loop), ${fmt(one, 1)} s of machine time each` +
      (offset ? `, turning at ${fmt(offset, 0)} rpm: about ${fmt(travel, 1)} ${unit} and back each time` : ", holding its position") +
      `; on a copy the new values are measured a third time. Nothing changes on the machine until you apply them on trial.`;
  } else if (name === "drive-trace") {
    const distance = num(body.distance, 5);
    text =
      `${axis.name}'s drive is recorded for ${fmt(num(body.duration_s, 0.5), 3)} s at ${fmt(1 / ts, 0)} Hz` +
      (distance ? ` while it moves ${fmt(distance, 2)} ${unit}; then it goes back.` : ", at rest.");
  } else {
    const speed = num(body.loop, 1) === 1;
    const seconds = num(body.duration_s, 0.5);
    text = speed
      ? `${axis.name}'s motor steps to ${fmt(num(body.speed_rpm, 50), 0)} rpm for ${fmt(seconds, 2)} s ` +
        `(about ${fmt(((num(body.speed_rpm, 50) / 60) * drive.mmPerRev * seconds), 1)} ${unit}), then goes back.`
      : `${axis.name} steps ${fmt(num(body.position_mm, 0.05), 3)} ${unit} for ${fmt(seconds, 2)} s and returns.`;
  }
  return (
    <p class="hint" data-testid="drive-plan" data-cascade="1" data-fits="1">
      {text}
      {props.live ? "" : " On a copy this takes a fraction of that; the machine itself moves only after you confirm."}
    </p>
  );
}

const PLANE_AXES: Record<number, [string, string]> = { 17: ["X", "Y"], 18: ["Z", "X"], 19: ["Y", "Z"] };

/** Why the circle cannot run in the chosen plane on this machine ("" when it can). */
export function circleProblem(body: Record<string, unknown>): string {
  const plane = num(body.plane, 18);
  const names = (status.value?.axes ?? []).filter((x) => x.kind === "linear").map((x) => x.name);
  const missing = (PLANE_AXES[plane] ?? []).filter((n) => !names.includes(n));
  return missing.length ? `G${plane} needs ${missing.join(" and ")}: this machine's linear axes are ${names.join(", ")}` : "";
}

/** The circle's motion: where, how far and how long (as nc_sim/assist/circle_test.py plans
 * it: out to the overrun's start, the overrun, the turn, the overrun, back to the centre). */
function CirclePlan(props: { body: Record<string, unknown>; live?: boolean }) {
  const b = props.body;
  const [a, c] = PLANE_AXES[num(b.plane, 18)] ?? ["?", "?"];
  const r = num(b.radius_mm, 10);
  const feed = num(b.feed_mm_min, 1000);
  const overrun = num(b.overrun_deg, 90);
  const both = num(b.direction, 0) === 0;
  const turn = (2 * Math.PI * r) / (feed / 60);
  // as the procedure plans it: the turn with its overruns, out and back, a second to settle
  const one = turn * (1 + (2 * overrun) / 360) + (2 * r) / (feed / 60) + 1;
  const unhomed = (status.value?.axes ?? []).filter((x) => (x.name === a || x.name === c) && !x.homed).map((x) => x.name);
  const problem = circleProblem(b);
  if (problem)
    return (
      <p class="assist-check off" data-testid="drive-plan" data-fits="0">
        {problem}: choose another plane.
      </p>
    );
  const dirs = both ? "counter-clockwise (G03), then clockwise (G02)" : num(b.direction, 0) === 3 ? "counter-clockwise (G03)" : "clockwise (G02)";
  return (
    <p class="hint" data-testid="drive-plan" data-fits="1">
      {a} and {c} run a circle of R{fmt(r, 3)} mm at F{fmt(feed, 0)} about where they stand (±{fmt(r, 3)} mm on both axes),
      {" "}{dirs}, with {fmt(overrun, 0)}° of overrun arc before and after the measured turn: one turn takes {fmt(turn, 1)} s,
      the whole run about {fmt((both ? 2 : 1) * one, 1)} s of machine time.
      {props.live ? "" : " On a copy this takes a fraction of that; the machine itself moves only after you confirm."}
      {props.live && unhomed.length ? (
        <b class="warn" data-testid="circle-unhomed">
          {" "}
          {unhomed.join(" and ")} {unhomed.length > 1 ? "are" : "is"} not homed: no software limit guards the circle.
        </b>
      ) : null}
    </p>
  );
}
