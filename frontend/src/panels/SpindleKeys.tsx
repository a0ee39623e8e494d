// The spindle's keys: S with M3/M4/M5 and M19 orientation, shared by the spindle panel and the
// scope's command strip (one set of checks and commands wherever they appear).
import { useEffect, useState } from "preact/hooks";
import type { AxisStatus } from "../api/types";
import { commandBlocked } from "../state/control";
import { motionLocked, online, status } from "../state/session";
import type { useCommand } from "../ui/useCommand";

export function SpindleKeys(props: { sp: AxisStatus; run: ReturnType<typeof useCommand>["run"] }) {
  const { sp, run } = props;
  // S shows the programmed speed (an MDI S600, a program's S) until the engineer types one
  const prog = sp.speed_prog_rpm ?? 0;
  const [speed, setSpeed] = useState(prog > 0 ? String(prog) : "1000");
  const [typed, setTyped] = useState(false);
  useEffect(() => {
    if (!typed && prog > 0) setSpeed(String(+prog.toFixed(1)));
  }, [prog, typed]);
  const [angle, setAngle] = useState("90");
  const [dir, setDir] = useState<"0" | "1" | "-1">("0");
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  const dis = !online.value || !!blocked;
  // offline, emergency stop or someone else's machine: nothing may start moving
  const locked = motionLocked.value || !!blocked;
  const lockedWhy = blocked || (status.value?.emergency_stop ? "emergency stop: reset first" : "");
  const rpm = Number(speed);
  const validS = speed.trim() !== "" && Number.isFinite(rpm) && rpm >= 0;
  // M3/M4 at the typed S; accepted, the field follows the programmed S again
  const start = async (m: 3 | 4): Promise<void> => {
    if ((await run({ type: "spindle", spindle: sp.name, m, speed_rpm: rpm })) !== null) setTyped(false);
  };
  const deg = Number(angle);
  const validAngle = angle.trim() !== "" && Number.isFinite(deg); // "" would be 0°
  return (
    <>
      <form
        class="row"
        onSubmit={(e) => {
          e.preventDefault();
          if (validS && !locked) void start(3);
        }}
      >
        <label>
          S <input data-testid="s-input" inputMode="decimal" value={speed} size={7} aria-invalid={!validS}
            onInput={(e) => {
              setSpeed((e.target as HTMLInputElement).value);
              setTyped(true);
            }} /> rpm
        </label>
        <button type="submit" data-testid="m3" disabled={locked || !validS} title={lockedWhy || "M3: clockwise"}>
          M3 ⟳
        </button>
        <button type="button" data-testid="m4" disabled={locked || !validS} title={lockedWhy || "M4: counter-clockwise"}
          onClick={() => void start(4)}>
          M4 ⟲
        </button>
        <button type="button" data-testid="m5" class="stop" disabled={dis} title={blocked}
          onClick={() => void run({ type: "spindle", spindle: sp.name, m: 5 })}>
          M5 stop
        </button>
      </form>
      <form
        class="row"
        onSubmit={(e) => {
          e.preventDefault();
          if (!validAngle || locked) return;
          void run({
            type: "spindle_position",
            spindle: sp.name,
            position_deg: deg,
            direction: dir === "0" ? null : (Number(dir) as 1 | -1),
          });
        }}
      >
        <label>
          M19 to <input data-testid="m19-angle" inputMode="decimal" value={angle} size={6} aria-invalid={!validAngle}
            onInput={(e) => setAngle((e.target as HTMLInputElement).value)} />°
        </label>
        <select aria-label="M19 direction" value={dir} onChange={(e) => setDir((e.target as HTMLSelectElement).value as "0")}>
          <option value="0">shortest way</option>
          <option value="1">M3 direction (+)</option>
          <option value="-1">M4 direction (−)</option>
        </select>
        <button type="submit" data-testid="m19" disabled={locked || !validAngle} title={lockedWhy}>
          M19 orient
        </button>
      </form>
      {/* its own line, reserved: the message appears without moving the buttons */}
      <div class="field-note">
        {!validAngle ? (
          <span class="inline-error" role="alert" data-testid="m19-angle-error">
            an angle in degrees is needed
          </span>
        ) : null}
      </div>
    </>
  );
}
