// Spindle: S with M3/M4/M5, M19 orientation, gear stages with their range bars, override,
// homing (kept apart from the motion buttons); for a main spindle with rotary-axis capability
// its mode (spindle S1 / rotary axis C) and the changeover [003 Fig. 4-1].
import { useEffect, useRef, useState } from "preact/hooks";
import { commandBlocked } from "../state/control";
import { loadList, paramsVersion } from "../state/params";
import type { AxisStatus, MachineStatus } from "../api/types";
import { loadRotaryAxisName, rotaryAxisName } from "../state/caxis";
import { machineId, motionLocked, online, status } from "../state/session";
import { AxisSignalLamps } from "../ui/AxisSignalLamps";
import { Panel } from "../ui/Panel";
import { fmt, gearName, qty } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";
import { GearBars, type GearRange } from "./GearBars";
import { SpindleKeys } from "./SpindleKeys";

interface SpindleParams {
  ranges: GearRange[];
  overrideMaxPct: number;
}

async function spindleParams(name: string): Promise<SpindleParams> {
  const [channel, own] = await Promise.all([loadList("channel", null), loadList("axis", name)]);
  const byName = new Map(channel.map((p) => [p.name, p.value]));
  const idx = [0, 1, 2, 3, 4, 5, 6, 7].find((i) => byName.get(`spindel[${i}].bezeichnung`) === name);
  const ranges: GearRange[] = [];
  if (idx !== undefined && byName.get("main_spindle_gear_change")) {
    for (let j = 0; j < 6; j++) {
      const pre = `spindel[${idx}].range_table[${j}]`;
      ranges.push({ min: Number(byName.get(`${pre}.min_speed`)), max: Number(byName.get(`${pre}.max_speed`)) });
    }
  }
  const ovr = own.find((p) => p.id === "P-AXIS-00109"); // kenngr.max_vb_override, 0.1 %
  return { ranges, overrideMaxPct: ovr ? Number(ovr.value) / 10 : 100 };
}

/** The mode of a main spindle with rotary-axis capability, the changeover in progress and the
 * #CAX / #CAX OFF keys (MDI blocks: the NC changes over as a program would). */
function ModeRow(props: { sp: AxisStatus; plc: MachineStatus["plc"]; locked: boolean; lockedWhy: string;
  run: ReturnType<typeof useCommand>["run"] }) {
  const { sp, plc } = props;
  const c = rotaryAxisName.value ?? (sp.spindle_mode === "rotary" ? sp.display_name : "C");
  const mode =
    sp.spindle_mode === "rotary"
      ? `rotary axis ${sp.display_name}`
      : sp.spindle_mode === "spindle"
        ? `spindle ${sp.name}`
        : sp.changeover != null
          ? "changing over"
          : "none";
  const noneWhy =
    "the PLC acknowledges neither mode (or both, ROTMOD_Q and SPMOD_Q): the next command that needs one changes over";
  // in the external phase the request the NC has set names the mode and the acknowledgement
  // it waits for (before, the requests still show the mode left)
  const external = sp.changeover === "external";
  const request = !external ? null : plc.signals?.ROTMOD ? "ROTMOD" : plc.signals?.SPMOD ? "SPMOD" : null;
  const target = request === "SPMOD" ? ` to spindle ${sp.name}` : request === "ROTMOD" ? ` to rotary axis ${c}` : "";
  const phase =
    sp.changeover === "internal"
      ? "braking, drive parameter record (internal changeover)"
      : sp.changeover === "external"
        ? `waiting for ${request ?? "the PLC"}_Q from the PLC`
        : sp.changeover === "interrupted"
          ? "interrupted: reset, or a jog or spindle key"
          : "";
  const busy = sp.changeover != null;
  const whyRotary = props.lockedWhy || (busy ? "a changeover is in progress" : sp.spindle_mode === "rotary" ? `already rotary axis ${c}` : "");
  const whySpindle = props.lockedWhy || (busy ? "a changeover is in progress" : sp.spindle_mode === "spindle" ? `already spindle ${sp.name}` : "");
  return (
    <div class="mode-row">
      <div class="row">
        <span>
          Mode{" "}
          <b data-testid="spindle-mode" data-mode={sp.spindle_mode}
            title={sp.spindle_mode === "none" && sp.changeover == null ? noneWhy : undefined}>
            {mode}
          </b>
        </span>
        {busy ? (
          <span class={`changeover ${sp.changeover}`} data-testid="spindle-changeover" role="status">
            changeover{target}: {phase}
          </span>
        ) : null}
      </div>
      <div class="row">
        <button type="button" data-testid="cax-on" disabled={props.locked || !!whyRotary}
          title={whyRotary || `#CAX: change over to the rotary axis ${c} (a turning spindle brakes first)`}
          onClick={() => void props.run({ type: "mdi", block: "#CAX" })}>
          #CAX → rotary axis {c}
        </button>
        <button type="button" data-testid="cax-off" disabled={props.locked || !!whySpindle}
          title={whySpindle || `#CAX OFF: change over to the spindle ${sp.name}`}
          onClick={() => void props.run({ type: "mdi", block: "#CAX OFF" })}>
          #CAX OFF → spindle {sp.name}
        </button>
        <span class="hint">
          {busy ? "" : sp.spindle_mode === "rotary" ? `M3/M4/M5/M19 and the gear keys change over to spindle ${sp.name} first` : `G00–G03 with ${c} or a jog of ${c} change over to the rotary axis`}
        </span>
      </div>
    </div>
  );
}

export function SpindlePanel() {
  const spindles = status.value?.axes.filter((a) => a.kind === "spindle") ?? [];
  const [name, setName] = useState("");
  const sp = spindles.find((a) => a.name === name) ?? spindles[0];
  const [params, setParams] = useState<SpindleParams | null>(null);
  const cmd = useCommand();
  const ovrTimer = useRef<number | null>(null);
  const [ovr, setOvr] = useState<number | null>(null);

  useEffect(() => void loadRotaryAxisName(), [machineId.value, paramsVersion.value]);
  useEffect(() => {
    if (sp) void spindleParams(sp.name).then(setParams, () => setParams(null));
  }, [sp?.name, machineId.value, paramsVersion.value]);

  if (!sp) return <Panel title="Spindle" id="spindle">No spindle on this machine.</Panel>;
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  const dis = !online.value || !!blocked;
  // offline, emergency stop or someone else's machine: nothing may start moving
  const locked = motionLocked.value || !!blocked;
  const lockedWhy = blocked || (status.value?.emergency_stop ? "emergency stop: reset first" : "");

  function sendOverride(pct: number) {
    setOvr(pct);
    if (ovrTimer.current !== null) return; // at most one write per 100 ms while dragging
    ovrTimer.current = window.setTimeout(() => {
      ovrTimer.current = null;
    }, 100);
    void cmd.run({ type: "override", axis: sp!.name, percent: pct });
  }

  const overridePct = ovr ?? sp.override_pct;
  const rotary = sp.spindle_mode === "rotary";
  return (
    <Panel
      title={rotary ? `Rotary axis ${sp.display_name} (spindle ${sp.name})` : `Spindle ${sp.name}`}
      id="spindle"
      actions={
        spindles.length > 1 ? (
          <select value={sp.name} onChange={(e) => setName((e.target as HTMLSelectElement).value)}>
            {spindles.map((a) => (
              <option key={a.name}>{a.name}</option>
            ))}
          </select>
        ) : null
      }
    >
      <div class="readouts">
        <span>
          S prog <b data-testid="spindle-prog">{fmt(sp.speed_prog_rpm, 0)}</b> rpm
        </span>
        <span>
          {rotary ? "v act" : "n act"} <b data-testid="spindle-speed">{fmt(sp.vel_act, 1)}</b>{" "}
          {rotary ? "°/min" : "rpm"}
        </span>
        <span class="pos">
          {rotary ? sp.display_name : "position"} <b data-testid="spindle-pos">{fmt(sp.pos_act, rotary ? 3 : 2)}</b>°
        </span>
        <span class="wordy">
          state <b>{sp.state}</b>
        </span>
      </div>
      {sp.spindle_mode != null && status.value ? (
        <ModeRow sp={sp} plc={status.value.plc} locked={locked} lockedWhy={lockedWhy} run={cmd.run} />
      ) : null}
      <AxisSignalLamps a={sp} />
      <SpindleKeys sp={sp} run={cmd.run} />
      <div class="gears">
        <div class="row">
          <span>
            Gear stage <b data-testid="spindle-gear">{sp.gear ? `M${39 + sp.gear}` : "—"}</b>
          </span>
          {params?.ranges.map((_, i) => (
            <button key={i} type="button" data-testid={`gear-m${40 + i}`} class={sp.gear === i + 1 ? "active" : ""}
              disabled={locked} title={lockedWhy || gearName(i + 1)} aria-pressed={sp.gear === i + 1}
              onClick={() => void cmd.run({ type: "gear", spindle: sp.name, m: 40 + i })}>
              M{40 + i}
            </button>
          ))}
        </div>
        {params?.ranges.length ? (
          <>
            <GearBars ranges={params.ranges} active={sp.gear ?? null} speed={sp.speed_prog_rpm ?? null} />
            <p class="hint" data-testid="gear-mapping">
              M40…M45 = gear 1…6 = gear records getriebe[0]…[5] (range_table[0]…[5])
              {sp.gear ? <> · now <b>{gearName(sp.gear)}</b></> : null}
            </p>
          </>
        ) : (
          <p class="hint">No gear change on this spindle.</p>
        )}
      </div>
      <div class="row">
        <label class="slider">
          Override{" "}
          <input type="range" data-testid="spindle-override" min={0} max={params?.overrideMaxPct ?? 100} step={0.1}
            value={overridePct} disabled={dis} title={blocked}
            onInput={(e) => sendOverride(Number((e.target as HTMLInputElement).value))}
            onChange={(e) => {
              const pct = Number((e.target as HTMLInputElement).value);
              setOvr(null);
              void cmd.run({ type: "override", axis: sp.name, percent: pct });
            }} />
          <b>{qty(overridePct, 1, "%")}</b>{" "}
          <span class="hint">max {qty(params?.overrideMaxPct, 1, "%")} (P-AXIS-00109)</span>
        </label>
      </div>
      <div class="row apart">
        <button type="button" data-testid="spindle-home" class="secondary" disabled={locked} title={lockedWhy}
          onClick={() => void cmd.run({ type: "home", axis: sp.name })}>
          G74 home spindle
        </button>
        <span class="hint">{sp.homed ? "homed" : "not homed"}</span>
      </div>
      <RefusalLine refusal={cmd.refusal} id="spindle-refusal" />
    </Panel>
  );
}
