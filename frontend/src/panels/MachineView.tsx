// Every axis and spindle with positions, speeds, lag, state and gear; the HLI lamps.
import type { AxisStatus } from "../api/types";
import { status } from "../state/session";
import { Lamp } from "../ui/Lamp";
import { Panel } from "../ui/Panel";
import { fmt, qty, velUnit } from "../ui/format";

function AxisRow({ a }: { a: AxisStatus }) {
  const spindle = a.kind === "spindle";
  const posDec = spindle ? 2 : 3;
  return (
    <tr data-testid={`axis-${a.name}`} class={a.job_error ? "has-error" : ""}>
      {/* the name follows the mode: C while the main spindle is the rotary axis [003 §2.4] */}
      <th scope="row" data-testid={`name-${a.name}`}>{a.display_name}</th>
      <td class="state" data-testid={`state-${a.name}`}>{a.state}</td>
      <td class="num pos" data-testid={`pos-${a.name}`}>
        {fmt(a.pos_act, posDec)}
      </td>
      <td class="num pos">{fmt(a.pos_cmd, posDec)}</td>
      <td class="num" data-testid={`lag-${a.name}`}>
        {fmt(a.lag, 4)}
      </td>
      <td class="unit">{a.unit === "deg" ? "°" : a.unit}</td>
      <td class="num" data-testid={`vcmd-${a.name}`}>
        {fmt(a.vel_cmd, 1)}
      </td>
      <td class="num" data-testid={`vact-${a.name}`}>
        {fmt(a.vel_act, 1)}
      </td>
      <td class="unit">{velUnit(a.unit === "deg" ? "°" : a.unit, a.kind, a.spindle_mode)}</td>
      <td data-testid={`gear-${a.name}`}>{a.gear ? `M${39 + a.gear}` : "—"}</td>
      <td title={a.homed ? "homed" : "not homed"}>{a.homed ? "✓" : "✗"}</td>
    </tr>
  );
}

/** A G74 on its way [002 §2.7]: its phase, how far it went and what is left where the NC
 * knows it (a search does not know where the cam is), and the phase's speed. */
function HomingLine({ a }: { a: AxisStatus }) {
  const h = a.homing;
  if (!h) return null;
  const unit = a.unit === "deg" ? "°" : a.unit;
  return (
    <p class="homing-line" role="status" data-testid={`homing-${a.name}`}>
      <b>G74 {a.display_name}</b>: <span data-testid={`homing-phase-${a.name}`}>{h.phase}</span> ·{" "}
      <span data-testid={`homing-moved-${a.name}`}>{fmt(Math.abs(h.moved), 1)}</span>&nbsp;{unit} from the start
      {h.to_go !== null && h.to_go !== undefined ? (
        <>
          {" "}· <span data-testid={`homing-to-go-${a.name}`}>{fmt(Math.abs(h.to_go), 1)}</span>&nbsp;{unit} to ref_pos
        </>
      ) : null}{" "}
      · at <span data-testid={`homing-speed-${a.name}`}>{qty(h.speed, 0, velUnit(unit, a.kind, a.spindle_mode))}</span>
    </p>
  );
}

export function MachineView() {
  const s = status.value;
  if (!s) return <Panel title="Machine" id="machine">Waiting for the service…</Panel>;
  const spindles = s.axes.filter((a) => a.kind === "spindle");
  const feedhold = !!s.channel_units.feedhold;
  const allEnabled = s.axes.every((a) => a.enabled);
  // the drives' own status [004 §4.2] (null: the drive type does not report that signal)
  const driveMissing = s.axes.flatMap((a) => [
    ...(a.ready_for_power_on === false ? [`${a.name}: ready_for_power_on`] : []),
    ...(a.ready_for_control_loop_on === false ? [`${a.name}: ready_for_control_loop_on`] : []),
  ]);
  return (
    <Panel title={`Machine ${s.name}`} id="machine">
      <table class="axes">
        <thead>
          <tr>
            <th>Axis</th>
            <th>State</th>
            <th class="num">Actual</th>
            <th class="num">Command</th>
            <th class="num">Lag</th>
            <th><span class="sr-only">Unit</span></th>
            <th class="num">v cmd</th>
            <th class="num">v act</th>
            <th><span class="sr-only">Speed unit</span></th>
            <th>Gear</th>
            <th>Homed</th>
          </tr>
        </thead>
        <tbody>
          {s.axes.map((a) => (
            <AxisRow a={a} key={a.name} />
          ))}
        </tbody>
      </table>
      {s.axes.map((a) => (
        <HomingLine a={a} key={a.name} />
      ))}
      <div class="lamps" aria-label="HLI state">
        {spindles.map((a) => (
          <div class="lamp-row" key={a.name}>
            <b>{a.display_name}</b>
            <Lamp id={`lamp-speed-reached-${a.name}`} on={a.speed_reached} label="speed reached" />
            <Lamp id={`lamp-stopped-${a.name}`} on={a.stopped} label="stopped" tone="info" />
            <Lamp id={`lamp-in-position-${a.name}`} on={a.in_position} label="in position" tone="info" />
            <Lamp
              id={`lamp-monitoring-${a.name}`}
              on={a.speed_monitoring_invalid}
              label="speed monitoring invalid"
              tone="warn"
            />
          </div>
        ))}
        <div class="lamp-row">
          <b>Channel</b>
          <Lamp id="lamp-job-error" on={s.job_errors.length > 0} label="job error" tone="bad" />
          <Lamp
            id="lamp-enables"
            on={allEnabled}
            label="enables"
            title={s.axes.flatMap((a) => a.missing_enables.map((m) => `${a.name}: ${m}`)).join(", ") || "all present"}
          />
          <Lamp id="lamp-drive-ready" on={s.plc.drives_powered && !driveMissing.length} label="drive ready"
            title={driveMissing.join(", ") || "every drive reports ready"} />
          <Lamp id="lamp-feedhold" on={feedhold} label="feedhold" tone="warn" />
          <Lamp id="lamp-estop" on={s.emergency_stop} label="emergency stop" tone="bad" />
        </div>
      </div>
    </Panel>
  );
}
