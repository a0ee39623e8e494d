// HLI objects of every axis and the channel, live; switches for the writable control units;
// the PLC's mode and its pending M functions with a manual acknowledge.
import { useState } from "preact/hooks";
import type { HliUnit } from "../api/types";
import { commandBlocked } from "../state/control";
import { online, status } from "../state/session";
import { Lamp } from "../ui/Lamp";
import { Panel } from "../ui/Panel";
import { fmt, qty } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";

const NUMERIC = new Set(["override"]); // written with the override sliders, not a switch

function Switch(props: { unit: string; value: number; axis: string | null; run: ReturnType<typeof useCommand>["run"] }) {
  const on = props.value !== 0;
  const id = `hli-${props.axis ?? "channel"}-${props.unit}`;
  const blocked = commandBlocked.value;
  return (
    <label class="switch" data-testid={id} title={blocked}>
      <input type="checkbox" role="switch" checked={on} disabled={!online.value || !!blocked}
        onChange={() => void props.run({ type: "hli", unit: props.unit as HliUnit, value: on ? 0 : 1, axis: props.axis })} />
      {props.unit} <span class="hint">{on ? "1" : "0"}</span>
    </label>
  );
}

export function HliPanel() {
  const s = status.value;
  const cmd = useCommand();
  const [delay, setDelay] = useState("");
  if (!s) return <Panel title="HLI / PLC" id="hli">Waiting for the service…</Panel>;
  const plc = s.plc;
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  return (
    <Panel title="HLI / PLC" id="hli">
      <div class="hli-grid">
        {s.axes.map((a) => (
          <fieldset key={a.name} class="hli-axis">
            <legend>{a.name}</legend>
            <div class="lamps">
              <Lamp on={a.enabled} label="enables" title={a.missing_enables.join(", ")} />
              <Lamp on={a.homed} label="homed" tone="info" />
              <Lamp on={a.in_position} label="in position" tone="info" />
              {a.kind === "spindle" ? (
                <>
                  <Lamp on={a.speed_reached} label="speed reached" />
                  <Lamp on={a.stopped} label="stopped" tone="info" />
                  <Lamp on={a.speed_monitoring_active} label="monitoring active" tone="info" />
                  <Lamp on={a.speed_monitoring_invalid} label="monitoring invalid" tone="warn" />
                </>
              ) : null}
              <Lamp on={a.job_error !== 0} label={`job error ${a.job_error || ""}`} tone="bad" />
            </div>
            <div class="hint">
              state {a.state} · loop <span data-testid={`hli-loop-${a.name}`}>{a.loop}</span> · override{" "}
              {qty(a.override_pct, 1, "%")}
            </div>
            <div class="switches">
              {Object.entries(a.control_units)
                .filter(([u]) => !NUMERIC.has(u))
                .map(([u, v]) => (
                  <Switch key={u} unit={u} value={v} axis={a.name} run={cmd.run} />
                ))}
            </div>
          </fieldset>
        ))}
        <fieldset class="hli-axis">
          <legend>Channel</legend>
          <div class="hint">
            path override {qty((s.channel_units.override ?? 1000) / 10, 1, "%")} · queued blocks {s.queued_blocks}
          </div>
          <div class="switches">
            {Object.entries(s.channel_units)
              .filter(([u]) => !NUMERIC.has(u))
              .map(([u, v]) => (
                <Switch key={u} unit={u} value={v} axis={null} run={cmd.run} />
              ))}
          </div>
        </fieldset>
        <fieldset class="hli-axis" data-testid="plc">
          <legend>PLC</legend>
          <div class="row">
            <label>
              Mode{" "}
              <select data-testid="plc-mode" value={plc.mode} disabled={!online.value || !!blocked} title={blocked}
                onChange={(e) => void cmd.run({ type: "plc_mode", mode: (e.target as HTMLSelectElement).value as "auto", delay_s: delay ? Number(delay) : null })}>
                <option value="auto">auto acknowledge</option>
                <option value="manual">manual acknowledge</option>
                <option value="fault">fault (never answers)</option>
              </select>
            </label>
            <label>
              delay <input size={5} inputMode="decimal" placeholder={fmt(plc.ack_delay_s, 3)} value={delay}
                onInput={(e) => setDelay((e.target as HTMLInputElement).value)} /> s
            </label>
            <Lamp id="lamp-drives-powered" on={plc.drives_powered} label="drives powered"
              title="every drive switched on, ready and enabled (DriveOn, TorquePermission)" />
          </div>
          <table class="pending-m">
            <thead>
              <tr>
                <th>Pending M</th>
                <th>Axis</th>
                <th>since cycle</th>
                <th />
              </tr>
            </thead>
            <tbody>
              {plc.pending.map((p) => (
                <tr key={`${p.m}-${p.out_cycle}`} data-testid={`pending-m${p.m}`}>
                  <td>M{p.m}</td>
                  <td>{p.axis}</td>
                  <td>{p.out_cycle}</td>
                  <td>
                    <button type="button" data-testid={`ack-m${p.m}`} disabled={!online.value || !!blocked} title={blocked}
                      onClick={() => void cmd.run({ type: "plc_ack", m: p.m })}>
                      Acknowledge
                    </button>
                  </td>
                </tr>
              ))}
              {!plc.pending.length ? (
                <tr>
                  <td colSpan={4} class="hint">
                    none
                  </td>
                </tr>
              ) : null}
            </tbody>
          </table>
        </fieldset>
      </div>
      <RefusalLine refusal={cmd.refusal} id="hli-refusal" />
    </Panel>
  );
}
