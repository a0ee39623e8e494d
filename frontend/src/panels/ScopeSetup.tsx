// Scope setup: channels, record length, pre-trigger, mode, trigger (level or event); arm,
// force, stop; the scope's state; continuous recording of the channels to a Rerun .rrd.
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { EventTrigger, LevelTrigger, RecordingInfo, ScopeSetup as Setup } from "../api/types";
import {
  arm,
  DEFAULT_CHANNELS,
  force,
  MAX_CHANNELS,
  MAX_DRIVE_S,
  saveDraft,
  scopeDraft,
  scopeStatus,
  startRecording,
  stop,
  stopRecording,
} from "../state/scope";
import { axisOutline, online } from "../state/session";
import { catalogue } from "../state/telemetry";
import { Panel } from "../ui/Panel";
import { may, standing } from "../state/control";
import { me } from "../state/auth";
import { SignalPicker } from "../ui/SignalPicker";

const EVENTS: [EventTrigger["event"], string][] = [
  ["m_start", "M function start"],
  ["m19_done", "M19 done"],
  ["gear_change", "gear change"],
  ["job_error", "job error"],
  ["speed_reached", "speed reached"],
];
const M_FUNCTIONS = [3, 4, 5, 19, 40, 41, 42, 43, 44, 45];
const STATE_TEXT: Record<string, string> = {
  idle: "idle",
  roll: "rolling",
  armed: "armed: waiting for the trigger",
  triggered: "triggered: recording",
  done: "done",
};

function kib(n: number): string {
  return n > 1 << 20 ? `${(n / (1 << 20)).toFixed(1)} MiB` : `${Math.round(n / 1024)} KiB`;
}

export function ScopeSetup() {
  const draft = scopeDraft.value;
  const [error, setError] = useState("");
  const [recording, setRecording] = useState<RecordingInfo | null>(null);
  const st = scopeStatus.value;
  const rec = st?.recording ?? recording;
  const setDraft = saveDraft;
  const trig = draft.trigger ?? null;
  // a trigger is the NC's: at the drive's rate the first NC signal of the captured axis
  const ncNames = new Set(catalogue.value.map((c) => c.name));
  const driveAxis = draft.rate === "drive" ? (draft.channels[0] ?? "").split(".")[0] : "";
  const firstNc = driveAxis ? catalogue.value.find((c) => c.axis === driveAxis)?.name : draft.channels[0];
  const level: LevelTrigger =
    trig?.type === "level" && ncNames.has(trig.signal)
      ? trig
      : { type: "level", signal: firstNc ?? catalogue.value[0]?.name ?? "", level: 0, edge: "rising", hysteresis: 0 };
  const event: EventTrigger = trig?.type === "event" ? trig : { type: "event", event: "m_start", axis: null, m: null };
  const axes = axisOutline.value.map((a) => a.name);
  const driveRate = draft.rate === "drive";
  const driveSignals = (st?.drive_channels ?? []).map((c) => ({ name: c.name, axis: c.name.split(".")[0] }));

  /** Switch the rate: a drive-rate capture records one axis' drive signals, single or
   * normal, up to 2 s; back at the NC's rate the default channels come back. */
  function setRate(rate: "nc" | "drive") {
    if (rate === draft.rate) return;
    if (rate === "drive") {
      const axis = driveSignals[0]?.axis ?? "X";
      const channels = ["speed_set_rpm", "speed_motor_rpm", "torque_nm"].map((n) => `${axis}.drive.${n}`);
      const mode = draft.mode === "roll" ? "single" : draft.mode;
      setDraft({ ...draft, rate, channels, mode, length_s: Math.min(draft.length_s, MAX_DRIVE_S), trigger: draft.trigger ?? event });
    } else {
      setDraft({ ...draft, rate, channels: DEFAULT_CHANNELS });
    }
  }

  async function run(f: () => Promise<unknown>) {
    setError("");
    try {
      await f();
    } catch (e) {
      setError(e instanceof ApiError ? e.refusal.message : String(e));
    }
  }

  const num = (e: Event) => Number((e.target as HTMLInputElement).value);
  const state = st?.state ?? "idle";
  const fill = st && st.length_cycles ? Math.min(1, st.filled_cycles / st.length_cycles) : 0;
  // the scope is whoever armed it while it records: another's is never silently replaced
  const owner = st?.armed_by ?? null;
  const busy = state === "armed" || state === "triggered" || state === "roll";
  const others = busy && owner !== null && !owner.startsWith(`${me.value?.name ?? ""} (`);
  const mayTakeOver = may("take_control") || standing.value === "mine";
  const watchOnly = !may("capture"); // a share link's guest: the scope is for the people at the machine
  const notYours = watchOnly
    ? "a share link only watches: it shows the traces, it does not record"
    : others
      ? `the scope is ${owner}'s and still records${mayTakeOver ? "" : ": ask them (the control holder, an instructor or an admin may take it over)"}`
      : "";

  return (
    <Panel title="Scope" id="scope-setup">
      <div class="scope-form">
        {/* the keys first: the signal picker opens downward over what follows it */}
        <div class="scope-buttons">
          <button type="button" class="primary" data-testid="scope-arm" disabled={watchOnly || !online.value || !draft.channels.length || (others && !mayTakeOver)}
            title={notYours} onClick={() => void run(() => arm(draft.mode === "roll" ? { ...draft, trigger: null } : draft, others))}>
            {others ? "Take over and arm" : draft.mode === "roll" ? "▶ Roll" : "◉ Arm"}
          </button>
          <button type="button" data-testid="scope-force" disabled={watchOnly || state !== "armed" || (others && !mayTakeOver)} title={notYours} onClick={() => void run(force)}>
            ⚡ Force
          </button>
          <button type="button" data-testid="scope-stop" disabled={watchOnly || state === "idle" || state === "done" || (others && !mayTakeOver)} title={notYours}
            onClick={() => void run(stop)}>
            ■ Stop
          </button>
        </div>
        <div class="scope-state" data-testid="scope-state" data-state={state}>
          <b>{STATE_TEXT[state]}</b>
          {st?.setup && state !== "idle" ? (
            <span>
              {" "}· {st.length_cycles} NC cycles, {st.pre_cycles} before the trigger
              {st.setup.rate === "drive" ? ", every drive step of them sampled" : ""}
              {state === "armed" || state === "roll" ? ` · history ${Math.round(fill * 100)} %` : ""}
            </span>
          ) : null}
          {owner && state !== "idle" ? (
            <span data-testid="scope-owner" class={others ? "scope-others" : ""}>
              {" "}· armed by {others ? owner : "you"}
              {st?.armed_unix ? ` at ${new Date(st.armed_unix * 1000).toLocaleTimeString()}` : ""}
              {others ? ` (their setup: ${st?.setup?.channels.join(", ") ?? ""})` : ""}
            </span>
          ) : null}
        </div>
        {error ? (
          <p class="refusal" role="alert" data-testid="scope-error">{error}</p>
        ) : null}
        <label>
          Rate
          <select value={draft.rate ?? "nc"} data-testid="scope-rate"
            onChange={(e) => setRate((e.target as HTMLSelectElement).value as "nc" | "drive")}>
            <option value="nc">every NC cycle</option>
            <option value="drive">drive rate, one axis (≤ {MAX_DRIVE_S} s)</option>
          </select>
        </label>
        <SignalPicker chosen={draft.channels} max={MAX_CHANNELS} testid="scope-channels"
          signals={driveRate ? driveSignals : undefined}
          onChange={(channels) => setDraft({ ...draft, channels })} />
        <label>
          Record length
          <input type="number" min={0.01} max={driveRate ? MAX_DRIVE_S : 60} step={0.1} value={draft.length_s} data-testid="scope-length"
            onInput={(e) => setDraft({ ...draft, length_s: num(e) })} /> s
        </label>
        <label>
          Pre-trigger
          <input type="number" min={0} max={100} step={5} value={draft.pretrigger_pct} data-testid="scope-pretrigger"
            onInput={(e) => setDraft({ ...draft, pretrigger_pct: num(e) })} /> %
        </label>
        <label>
          Mode
          <select value={draft.mode} data-testid="scope-mode"
            onChange={(e) => setDraft({ ...draft, mode: (e.target as HTMLSelectElement).value as Setup["mode"] })}>
            <option value="single">single</option>
            <option value="normal">normal (re-arms)</option>
            <option value="roll" disabled={driveRate} title={driveRate ? "a drive-rate capture is a trace of up to 2 s: single or normal" : undefined}>
              roll (free running){driveRate ? " — not at the drive's rate" : ""}
            </option>
          </select>
        </label>
        <fieldset class="trigger" disabled={draft.mode === "roll"}>
          <legend>Trigger</legend>
          <label>
            <input type="radio" name="trigger-type" checked={trig?.type !== "level"} data-testid="trigger-event"
              onChange={() => setDraft({ ...draft, trigger: event })} /> event
          </label>
          <label>
            <input type="radio" name="trigger-type" checked={trig?.type === "level"} data-testid="trigger-level"
              onChange={() => setDraft({ ...draft, trigger: level })} /> level
          </label>
          {trig?.type === "level" ? (
            <div class="trigger-fields">
              <select value={level.signal} data-testid="trigger-signal"
                onChange={(e) => setDraft({ ...draft, trigger: { ...level, signal: (e.target as HTMLSelectElement).value } })}>
                {catalogue.value.map((s) => (
                  <option key={s.name} value={s.name}>{s.name}</option>
                ))}
              </select>
              <select value={level.edge} data-testid="trigger-edge"
                onChange={(e) => setDraft({ ...draft, trigger: { ...level, edge: (e.target as HTMLSelectElement).value as LevelTrigger["edge"] } })}>
                <option value="rising">↗ rising</option>
                <option value="falling">↘ falling</option>
              </select>
              <label>
                level <input type="number" step="any" value={level.level} data-testid="trigger-value"
                  onInput={(e) => setDraft({ ...draft, trigger: { ...level, level: num(e) } })} />
              </label>
              <label>
                hysteresis <input type="number" min={0} step="any" value={level.hysteresis} data-testid="trigger-hysteresis"
                  onInput={(e) => setDraft({ ...draft, trigger: { ...level, hysteresis: num(e) } })} />
              </label>
            </div>
          ) : (
            <div class="trigger-fields">
              <select value={event.event} aria-label="trigger event" data-testid="trigger-kind"
                onChange={(e) => setDraft({ ...draft, trigger: { ...event, event: (e.target as HTMLSelectElement).value as EventTrigger["event"] } })}>
                {EVENTS.map(([v, text]) => (
                  <option key={v} value={v}>{text}</option>
                ))}
              </select>
              <select value={event.axis ?? ""} data-testid="trigger-axis" aria-label="axis"
                onChange={(e) => setDraft({ ...draft, trigger: { ...event, axis: (e.target as HTMLSelectElement).value || null } })}>
                <option value="">any axis</option>
                {axes.map((a) => (
                  <option key={a} value={a}>{a}</option>
                ))}
              </select>
              {event.event === "m_start" ? (
                <select value={event.m ?? ""} data-testid="trigger-m" aria-label="M function"
                  onChange={(e) => {
                    const v = (e.target as HTMLSelectElement).value;
                    setDraft({ ...draft, trigger: { ...event, m: v ? Number(v) : null } });
                  }}>
                  <option value="">any M</option>
                  {M_FUNCTIONS.map((m) => (
                    <option key={m} value={m}>M{m}</option>
                  ))}
                </select>
              ) : null}
            </div>
          )}
        </fieldset>
        <fieldset class="recording">
          <legend>Continuous recording (.rrd)</legend>
          {rec?.active ? (
            <>
              <span data-testid="recording-state">
                ● recording {rec.signals.length} signals · {(rec.cycles / 1000).toFixed(1)} k cycles · {kib(rec.bytes)}
              </span>
              <button type="button" data-testid="recording-stop" onClick={() => void run(async () => setRecording(await stopRecording()))}>
                ■ Stop recording
              </button>
            </>
          ) : (
            <>
              <button type="button" data-testid="recording-start" disabled={!online.value || !draft.channels.length || driveRate || !may("record")}
              title={!may("record") ? "recording to disk takes the role operator or above" : driveRate ? "continuous recording is at the NC's rate: switch Rate to every NC cycle" : undefined}
                onClick={() => void run(async () => setRecording(await startRecording(draft.channels)))}>
                ● Record the channels
              </button>
              {driveRate ? <span class="hint">records at the NC's rate only</span> : null}
              {rec ? (
                <span>
                  last: {rec.cycles} cycles, {kib(rec.bytes)} ·{" "}
                  <a href={`/api/recordings/${rec.id}/recording.rrd`} download>.rrd</a> ·{" "}
                  <a href={`/api/recordings/${rec.id}/viewer`} target="_blank" rel="noreferrer">Rerun viewer</a>
                </span>
              ) : null}
            </>
          )}
        </fieldset>
      </div>
    </Panel>
  );
}
