// HLI objects of every axis and the channel, live; switches for the writable control units;
// the PLC's mode and its pending M functions with a manual acknowledge; the spindle/rotary-axis
// handshake ROTMOD/SPMOD -> ROTMOD_Q/SPMOD_Q [003 §4.1] with manual keys for the PLC's answers.
import { useState } from "preact/hooks";
import type { HliUnit, MachineStatus, PendingM } from "../api/types";
import { commandBlocked } from "../state/control";
import { answerOf, secondsLeft, waitedFor } from "../state/handshakes";
import { online, status } from "../state/session";
import { AxisSignalLamps } from "../ui/AxisSignalLamps";
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

type Run = ReturnType<typeof useCommand>["run"];
const ACKS = ["ROTMOD_Q", "SPMOD_Q"] as const;

/** The four handshake levels as lamps; in manual PLC mode keys to set or withdraw the PLC's
 * acknowledgements (withdrawing the one of the mode in force is a process error, 90031). */
function Handshake(props: { s: MachineStatus; run: Run; disabled: boolean; title: string }) {
  const sig = props.s.plc.signals ?? {};
  const manual = props.s.plc.mode === "manual";
  // the acknowledgement of the mode in force: the one the NC's request keeps asking for
  const inForce = (q: string) => !!sig[q] && !!sig[q.replace("_Q", "")];
  return (
    <div class="handshake" data-testid="handshake">
      <div class="row">
        <span class="hint dir">NC → PLC</span>
        <Lamp id="lamp-ROTMOD" on={sig.ROTMOD} label="ROTMOD" tone="info" title="the NC requests rotary axis mode" />
        <Lamp id="lamp-SPMOD" on={sig.SPMOD} label="SPMOD" tone="info" title="the NC requests spindle mode" />
      </div>
      <div class="row">
        <span class="hint dir">PLC → NC</span>
        <Lamp id="lamp-ROTMOD_Q" on={sig.ROTMOD_Q} label="ROTMOD_Q" title="the PLC acknowledges rotary axis mode" />
        <Lamp id="lamp-SPMOD_Q" on={sig.SPMOD_Q} label="SPMOD_Q" title="the PLC acknowledges spindle mode" />
        {manual
          ? ACKS.map((q) => (
              <button key={q} type="button" data-testid={`plc-signal-${q}`} class={sig[q] && inForce(q) ? "danger" : "secondary"}
                disabled={props.disabled}
                title={props.title || (sig[q] ? (inForce(q) ? `withdraw ${q}: the mode in force loses its acknowledgement — process error 90031` : `withdraw ${q}`) : `set ${q}`)}
                onClick={() => void props.run({ type: "plc_signal", signal: q, on: !sig[q] })}>
                {sig[q] ? "Withdraw" : "Set"} {q}
              </button>
            ))
          : null}
      </div>
      {manual ? (
        <p class="hint warn-note" role="note">
          ⚠ Withdrawing the acknowledgement of the mode in force (ROTMOD_Q in rotary axis mode, SPMOD_Q in spindle mode) is a
          process error (90031): the axis stops.
        </p>
      ) : (
        <p class="hint">The PLC answers {props.s.plc.mode === "auto" ? "by itself" : "never (fault)"}; manual acknowledge sets the signals by hand.</p>
      )}
    </div>
  );
}

/** A pending M function or mode request, the time left before the NC gives up (90004), and
 * its acknowledge key (state/handshakes.ts: the strip under the top bar shows the same). */
function PendingRow(props: { p: PendingM; run: Run; disabled: boolean; title: string }) {
  const { p } = props;
  const tid = p.signal ?? `m${p.m}`;
  const answer = answerOf(p);
  return (
    <tr data-testid={`pending-${tid}`}>
      <td>{waitedFor(p)}</td>
      <td>{p.axis}</td>
      <td>{p.out_cycle}</td>
      <td class="num">{qty(secondsLeft(p), 1, "s")}</td>
      <td>
        <button type="button" data-testid={`ack-${tid}`} disabled={props.disabled} title={props.title}
          onClick={() => void props.run(answer.cmd)}>
          {answer.label}
        </button>
      </td>
    </tr>
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
            <legend>
              {a.display_name}
              {a.display_name !== a.name ? <span class="hint"> (spindle {a.name})</span> : null}
            </legend>
            <div class="lamps">
              <Lamp on={a.enabled} label="enables" title={a.missing_enables.join(", ")} />
              {/* homed, in position, speed reached, stopped: the 003 §4.2 lamps below */}
              {a.kind === "spindle" ? (
                <>
                  <Lamp on={a.speed_monitoring_active} label="monitoring active" tone="info" />
                  <Lamp on={a.speed_monitoring_invalid} label="monitoring invalid" tone="warn" />
                </>
              ) : null}
              <Lamp on={a.job_error !== 0} label={`job error ${a.job_error || ""}`} tone="bad" />
            </div>
            <AxisSignalLamps a={a} />
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
          {Object.keys(plc.signals ?? {}).length ? (
            <Handshake s={s} run={cmd.run} disabled={!online.value || !!blocked} title={blocked} />
          ) : null}
          <table class="pending-m">
            <thead>
              <tr>
                <th>Pending</th>
                <th>Axis</th>
                <th>since cycle</th>
                <th>left</th>
                <th />
              </tr>
            </thead>
            <tbody>
              {plc.pending.map((p) => (
                <PendingRow key={`${p.signal ?? p.m}-${p.out_cycle}`} p={p} run={cmd.run} disabled={!online.value || !!blocked}
                  title={blocked} />
              ))}
              {!plc.pending.length ? (
                <tr>
                  <td colSpan={5} class="hint">
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
