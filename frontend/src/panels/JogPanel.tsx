// Jog: axis choice, press-and-hold +/−, incremental steps, jog feed, feed override, homing.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { heldKey, holdJog, jogSettings, keyName, releaseJog } from "../state/jog";
import { loadRotaryAxisName, rotaryAxisName } from "../state/caxis";
import { commandBlocked } from "../state/control";
import { loadList, numbers, paramsVersion } from "../state/params";
import { machineId, motionLocked, online, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { fmt, qty } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";

const STEPS = [0.001, 0.01, 0.1, 1, 10];

function JogKey(props: {
  axis: string;
  dir: 1 | -1;
  feed: number | null;
  disabled: boolean;
  title: string;
  onRefused: (r: Refusal) => void;
}) {
  const name = keyName(props.axis, props.dir);
  const active = heldKey.value === name;
  // a key's own events release only its own hold: pressing the other key moves the focus,
  // and the blur of this one must not end the hold just started there
  const release = () => releaseJog(name);
  // Chromium delivers pointer events to disabled buttons too: a locked key must not jog
  const start = () =>
    !props.disabled &&
    holdJog(props.axis, props.dir, props.feed, (e) =>
      props.onRefused(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
  return (
    <button
      type="button"
      class={`jogkey ${active ? "held" : ""}`}
      data-testid={`jog-${props.dir > 0 ? "plus" : "minus"}`}
      disabled={props.disabled}
      aria-pressed={active}
      title={props.title}
      onPointerDown={(e) => {
        (e.currentTarget as HTMLElement).setPointerCapture(e.pointerId);
        start();
      }}
      onPointerUp={release}
      onPointerCancel={release}
      onLostPointerCapture={release}
      onKeyDown={(e) => {
        if ((e.key === " " || e.key === "Enter") && !e.repeat) {
          e.preventDefault();
          start();
        }
      }}
      onKeyUp={(e) => (e.key === " " || e.key === "Enter") && release()}
      onBlur={release}
      onContextMenu={(e) => e.preventDefault()}
    >
      {props.dir > 0 ? "+" : "−"} {props.axis}
    </button>
  );
}

// the jog feed without one typed (the NC's own G200 default is the axis' rapid jog)
const SAFE_JOG_MM_MIN = 300;
const SAFE_JOG_DEG_MIN = 3600; // 10 rpm

export function JogPanel() {
  const axes = status.value?.axes ?? [];
  const { axis: name, feed, step } = jogSettings.value;
  const ax = axes.find((a) => a.name === name) ?? axes[0];
  const [jogRefusal, setJogRefusal] = useState<Refusal | null>(null);
  const cmd = useCommand();
  const [overrideMax, setOverrideMax] = useState(100);
  useEffect(() => {
    // the channel's max_vb_override (0.1 %) bounds the feed override
    if (!machineId.value) return;
    void numbers("channel", null).then((v) => setOverrideMax((v.get("max_vb_override") ?? 1000) / 10), () => undefined);
  }, [machineId.value, paramsVersion.value]);
  // the axis' G200 maximum (P-AXIS-00213) bounds the jog feed [002 §2.6.1]; the NC refuses a
  // feed above it as well (90025), this shows it before a key is pressed
  // and with the gear's getriebe.dynamik.vb_max the default feed a jog without one takes
  const [feedMax, setFeedMax] = useState<number | null>(null);
  const [feedDefault, setFeedDefault] = useState<number | null>(null);
  const [g201Max, setG201Max] = useState<number | null>(null); // the manual share under G201
  const axName = ax?.name;
  const gear = ax?.gear ?? 1;
  useEffect(() => {
    setFeedMax(null);
    setFeedDefault(null);
    setG201Max(null);
    if (!machineId.value || !axName) return;
    void loadList("axis", axName).then((list) => {
      // list unit × eng_factor = mm/min | °/min (rpm for a spindle, which jogs as C in °/min)
      const perMin = (n: string) => {
        const p = list.find((q) => q.name === n);
        if (!p || typeof p.value !== "number" || p.eng_factor == null) return null;
        const v = p.value * p.eng_factor;
        return p.eng_unit === "rpm" ? v * 360 : v;
      };
      const hb = perMin("handbetrieb.hb.vb_max");
      const dyn = perMin(`getriebe[${Math.max(0, gear - 1)}].dynamik.vb_max`);
      setFeedMax(hb);
      setFeedDefault(hb !== null && dyn !== null ? Math.min(hb, dyn) : hb);
      const share = list.find((q) => q.name === "handbetrieb.ipo.hb_proz_v_max")?.value;
      setG201Max(dyn !== null && typeof share === "number" ? (dyn * share) / 100 : null);
    }, () => undefined);
  }, [machineId.value, paramsVersion.value, axName, gear]);
  useEffect(() => void loadRotaryAxisName(), [machineId.value, paramsVersion.value]);
  if (!ax) return <Panel title="Jog" id="jog">Waiting for the service…</Panel>;
  // the main spindle with rotary-axis capability jogs as the rotary axis C: a jog changes it
  // over first [003 §2.3], then it moves in °/min under the feed override like any axis
  const cName = ax.spindle_mode != null ? (rotaryAxisName.value ?? (ax.spindle_mode === "rotary" ? ax.display_name : null)) : null;
  const jogName = cName ?? ax.name;
  const unit = ax.unit === "deg" ? "°" : "mm";
  // no feed typed: the HMI's safe jog feed, not the G200 default (10 000 mm/min took an
  // unhomed X 350 mm in a 2 s press); the engineer raises it consciously, up to G200's
  const safe = Math.min(ax.unit === "deg" ? SAFE_JOG_DEG_MIN : SAFE_JOG_MM_MIN, feedDefault ?? Infinity);
  const typed = feed === null || feed.trim() === "" ? null : Number(feed);
  const feedNum = typed ?? safe;
  const feedPositive = Number.isFinite(feedNum) && feedNum > 0;
  const feedInLimit = feedMax === null || feedNum <= feedMax * (1 + 1e-12);
  const feedOk = feedPositive && feedInLimit;
  const feedError = !feedPositive
    ? "a feed > 0 is needed (empty: the safe jog feed)"
    : !feedInLimit
      ? `at most ${qty(feedMax, 2, `${unit}/min`)}: the G200 maximum of ${ax.display_name} (P-AXIS-00213)`
      : "";
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  const dis = !online.value || !!blocked;
  // a jog feed the axis cannot take jogs nowhere (never at the default or the limit instead)
  const noMotion = motionLocked.value || !feedOk || !!blocked;
  const estopWhy = status.value?.emergency_stop ? "emergency stop: reset first" : "";
  const why = blocked || estopWhy || (feedError ? `jog feed: ${feedError}` : "");
  const pathOverride = (status.value?.channel_units.override ?? 1000) / 10;
  // G201 while the program's path runs: a jog of a path axis rides on the path with the manual
  // share of the axis' speed (hb_proz_v_max of vb_max) [002 §2.6.2]
  const ch = status.value?.channel;
  const pathAxis = ax.kind !== "spindle" || ax.spindle_mode === "rotary"; // C as a rotary axis
  const onPath = !!ch && ["running", "held", "block_end"].includes(ch.state) && pathAxis;
  const g201 = onPath && ch?.modal.manual_mode === "G201";
  return (
    <Panel title="Jog" id="jog">
      <div class="row" role="radiogroup" aria-label="axis">
        {axes.map((a) => (
          <label key={a.name} class={`axis-choice ${a.name === ax.name ? "active" : ""}`}>
            <input type="radio" name="jog-axis" value={a.name} checked={a.name === ax.name}
              onChange={() => jogSettings.patch({ axis: a.name })} data-testid={`jog-axis-${a.name}`} />
            {a.display_name}
          </label>
        ))}
        <span class="readout">
          {ax.display_name} = <b data-testid="jog-pos">{fmt(ax.pos_act, 3)}</b> {unit}
        </span>
      </div>
      <div class="row">
        {([-1, 1] as const).map((d) => (
          <JogKey key={d} axis={jogName} dir={d} feed={feedNum} disabled={noMotion} onRefused={setJogRefusal}
            title={why || "Hold to jog; release stops"} />
        ))}
        <label>
          Jog feed{" "}
          <input data-testid="jog-feed" inputMode="decimal" size={9} class={feed === null ? "is-default" : ""}
            value={feed ?? fmt(safe, 0)} aria-invalid={!feedOk}
            aria-describedby="jog-feed-default"
            onInput={(e) => jogSettings.patch({ feed: (e.target as HTMLInputElement).value })} />{" "}
          {unit}/min
        </label>
        {g201 ? (
          <span class="tag default-tag" data-testid="jog-g201"
            title="G201: a jog rides on the running path with the manual share of the axis' speed (hb_proz_v_max, P-AXIS-00083, of vb_max)">
            G201 on the path · up to {qty(g201Max, 1, `${unit}/min`)}
          </span>
        ) : null}
        {g201 ? null : feed === null ? (
          <span class="tag default-tag" id="jog-feed-default" data-testid="jog-feed-default"
            title={`the HMI's safe jog feed; type a higher one to go faster, up to ${qty(feedDefault, 0, `${unit}/min`)} (G200: hb.vb_max, P-AXIS-00213, at most the gear's vb_max)`}>
            safe default · G200 up to {qty(feedDefault, 0, `${unit}/min`)}
          </span>
        ) : (
          <button type="button" class="link" data-testid="jog-feed-reset" onClick={() => jogSettings.patch({ feed: null })}>
            ↺ default
          </button>
        )}
      </div>
      {cName && ax.spindle_mode !== "rotary" ? (
        <p class="hint" data-testid="jog-changeover-hint">
          A jog of {cName} changes {ax.name} over to the rotary axis {cName} first (M5 before, if it turns).
        </p>
      ) : null}
      {!ax.homed && ax.kind !== "spindle" && ax.state !== "HOMING" ? (
        <p class="warn-line" data-testid="jog-unhomed" role="note">
          {ax.display_name} is not homed: no software limits guard it. Jog at a low feed and watch the slide.
        </p>
      ) : null}
      <div class="field-note">
        {feedError ? (
          <span class="inline-error" role="alert" data-testid="jog-feed-error">
            {feedError}
          </span>
        ) : null}
      </div>
      <div class="row">
        <label>
          Increment{" "}
          <select data-testid="jog-step-size" value={String(step)} onChange={(e) => jogSettings.patch({ step: Number((e.target as HTMLSelectElement).value) })}>
            {STEPS.map((s) => (
              <option key={s} value={String(s)}>
                {s} {unit}
              </option>
            ))}
          </select>
        </label>
        {([-1, 1] as const).map((d) => (
          <button key={d} type="button" data-testid={`jog-step-${d > 0 ? "plus" : "minus"}`} disabled={noMotion} title={why}
            onClick={() => void cmd.run({ type: "jog", axis: jogName, action: "step", direction: d, distance: step, feed_mm_min: feedNum })}>
            {d > 0 ? "+" : "−"}
            {step} {unit}
          </button>
        ))}
      </div>
      <div class="row">
        <label class="slider">
          Feed override{" "}
          <input type="range" data-testid="feed-override" min={0} max={overrideMax} step={1} value={pathOverride} disabled={dis} title={blocked}
            onChange={(e) => void cmd.run({ type: "override", axis: null, percent: Number((e.target as HTMLInputElement).value) })} />
          <b>{qty(pathOverride, 1, "%")}</b>
        </label>
      </div>
      <div class="row apart">
        <button type="button" class="secondary" data-testid="jog-home" disabled={motionLocked.value || !!blocked}
          title={blocked || estopWhy}
          onClick={() => void cmd.run({ type: "home", axis: ax.name })}>
          G74 home {ax.name}
        </button>
        <span class="hint" data-testid="jog-homed">{ax.state === "HOMING" ? "homing…" : ax.homed ? "homed" : "not homed"}</span>
      </div>
      <RefusalLine refusal={cmd.refusal ?? jogRefusal} id="jog-refusal" />
    </Panel>
  );
}
