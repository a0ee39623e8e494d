// The service-axis view (SINUMERIK's service-axis screen, TwinCAT's axis dialogs): per axis and
// spindle at a glance. Positions, speeds, enables and status bits come from the pushed status;
// kv, expected lag, measured k, D/A and the limits in force from GET .../service-axes, read
// only while this tab is open.
import type { ComponentChildren } from "preact";
import { useEffect, useState } from "preact/hooks";
import { http } from "../api/http";
import type { AxisService, AxisStatus, LimitInForce, ServiceAxes } from "../api/types";
import { machineId, machineUrl, online, status } from "../state/session";
import { fmt, qty as withUnit, velUnit } from "../ui/format";
import { Lamp } from "../ui/Lamp";
import { Panel } from "../ui/Panel";

/** A value with its unit, or "—" alone where there is none (no unit beside a dash). */
const qty = (v: number | null | undefined, decimals: number, unit: string) =>
  v === null || v === undefined || !Number.isFinite(v) ? "—" : withUnit(v, decimals, unit);

const READ_MS = 250; // four reads a second: the view follows the machine, the worker hardly notices

/** The service view read every READ_MS while mounted (the tab is open); null until the first. */
function useServiceAxes(): ServiceAxes | null {
  const [view, setView] = useState<ServiceAxes | null>(null);
  const mid = machineId.value;
  useEffect(() => {
    if (!mid) return;
    let live = true;
    const read = async () => {
      try {
        const v = await http.get<ServiceAxes>(machineUrl("/service-axes"));
        if (live) setView(v);
      } catch {
        /* offline or gone: the connection banner says so; keep the last view */
      }
    };
    void read();
    const t = window.setInterval(() => void read(), READ_MS);
    return () => {
      live = false;
      window.clearInterval(t);
    };
  }, [mid]);
  return view;
}

function Row(props: { label: string; title?: string; id?: string; children: ComponentChildren }) {
  return (
    <tr title={props.title}>
      <th scope="row">{props.label}</th>
      <td class="num" data-testid={props.id}>
        {props.children}
      </td>
    </tr>
  );
}

const KIND_WORDS: Record<LimitInForce["kind"], string> = {
  parameter: "parameter",
  programmed: "programmed",
  reduced_speed: "reduced speed (PLC)",
  reduced_acceleration: "reduced acceleration (PLC)",
  tool: "tool",
};

function limitSource(l: LimitInForce): string {
  const id = l.param_id ? ` (${l.param_id})` : "";
  const ovr = l.override_pct != null ? ` × override ${fmt(l.override_pct, 0)} %` : "";
  return `${l.source}${id}${ovr}`;
}

function LimitRow(props: { label: string; limit: LimitInForce | null | undefined; none?: string | null; id: string; decimals: number }) {
  const l = props.limit;
  if (!l) {
    return (
      <Row label={props.label} id={props.id} title={props.none ?? undefined}>
        — <span class="svc-src">{props.none}</span>
      </Row>
    );
  }
  return (
    <Row label={props.label} id={props.id} title={`${KIND_WORDS[l.kind]}: ${limitSource(l)}`}>
      {qty(l.value, props.decimals, l.unit)}
      <span class="svc-src" data-testid={`${props.id}-source`}>
        {limitSource(l)}
      </span>
    </Row>
  );
}

// lr_hw[i].da_max at its default, the whole 32-bit range: a digital interface, no D/A
const NO_DA_LIMIT = 2147483647;

function AxisCard({ a, s }: { a: AxisStatus; s: AxisService | undefined }) {
  const unit = a.unit === "deg" ? "°" : a.unit;
  const vu = velUnit(a.unit, a.kind, a.spindle_mode);
  const id = (f: string) => `svc-${a.name}-${f}`;
  const daPct = s && s.da_max_digits > 0 ? (100 * Math.abs(s.da_digits)) / s.da_max_digits : null;
  const enables = Object.keys(a.control_units).filter((u) => ["DriveOn", "TorquePermission", "ReleaseFeedhold"].includes(u));
  return (
    <section class="svc-card" data-testid={`svc-${a.name}`} aria-label={`service view ${a.display_name}`}>
      <h3>
        {a.display_name} <span class="hint">{a.kind} · {a.state}</span>
      </h3>
      <table class="svc-table">
        <tbody>
          <Row label="Position cmd" id={id("pos-cmd")}>{qty(a.pos_cmd, 4, unit)}</Row>
          <Row label="Position act" id={id("pos-act")}>{qty(a.pos_act, 4, unit)}</Row>
          <Row label="Speed cmd" id={id("vel-cmd")}>{qty(a.vel_cmd, 1, vu)}</Row>
          <Row label="Speed act" id={id("vel-act")}>{qty(a.vel_act, 1, vu)}</Row>
          <Row label="Distance to go" id={id("to-go")}>{qty(a.distance_to_go, 4, unit)}</Row>
          <Row label="Lag" id={id("lag")}>{qty(a.lag, 4, unit)}</Row>
          <Row label="Expected lag v/kv" id={id("lag-expected")}
            title={s?.lag_expected_why_not ?? "steady state at constant speed: (1 − ff)·v / kv with the active gear record's kv"}>
            {qty(s?.lag_expected, 4, unit)}
          </Row>
          <Row label={`kv (gear ${s?.gear ?? "—"})`} id={id("kv")} title="getriebe[gear−1].kv of the active gear record">
            {qty(s?.kv_per_s, 2, "1/s")}
          </Row>
          <Row label="Measured k = v/lag" id={id("k")}
            title={s?.k_why_not ?? "averaged over 0.1 s after 8/kv at constant speed; equals kv when multi_gain matches the drive"}>
            {qty(s?.k_measured_per_s, 2, "1/s")}
          </Row>
          {s && s.ff_weight > 0 ? <Row label="Feedforward" id={id("ff")}>{qty(100 * s.ff_weight, 0, "%")}</Row> : null}
          {s && s.da_max_digits >= NO_DA_LIMIT ? (
            // a digital drive (SERCOS …) takes the command as a number: no D/A range to fill
            <Row label="Command value" id={id("da")} title="a digital drive interface: lr_hw.da_max gives no D/A range (2³¹ − 1)">
              {fmt(s.da_digits, 0)} digits <span class="svc-src">digital: no D/A range</span>
            </Row>
          ) : (
            <Row label="D/A output" id={id("da")} title={`lr_hw.da_max ${fmt(s?.da_max_digits, 0)} digits`}>
              {fmt(s?.da_digits, 0)} / {fmt(s?.da_max_digits, 0)} <span class="svc-src">{qty(daPct, 1, "%")}</span>
            </Row>
          )}
          <Row label="Override" id={id("override")}>{qty(a.override_pct, 0, "%")}</Row>
          <LimitRow label="Velocity limit" limit={s?.velocity} id={id("v-limit")} decimals={1} />
          <LimitRow label="Acceleration" limit={s?.acceleration} id={id("a-limit")} decimals={0} />
          <LimitRow label="Jerk" limit={s?.jerk} none={s?.jerk_why_none} id={id("j-limit")} decimals={0} />
        </tbody>
      </table>
      <div class="lamps signals" role="group" aria-label={`${a.display_name} enables and drive status`}>
        {enables.map((u) => (
          <Lamp key={u} id={id(`en-${u}`)} on={!!a.control_units[u]} label={u} title="drive enable (HLI control unit)" />
        ))}
        {a.ready_for_power_on != null ? (
          <Lamp id={id("rfpo")} on={a.ready_for_power_on} label="ready for power on" title="drive status [004 §4.2]" />
        ) : null}
        {a.ready_for_control_loop_on != null ? (
          <Lamp id={id("rfclo")} on={a.ready_for_control_loop_on} label="ready for control loop on" title="drive status [004 §4.2]" />
        ) : null}
        <Lamp id={id("homed")} on={a.homed} label="homed" tone="info" />
        <Lamp id={id("inpos")} on={a.in_position} label="in position" tone="info" />
        {/* lit on an error; unlit it reads "job error" (a lamp off labelled "no job error" read as the opposite) */}
        <Lamp id={id("error")} on={a.job_error !== 0} label={a.job_error ? `job error ${a.job_error}` : "job error"} tone="bad" />
      </div>
    </section>
  );
}

/** One card per axis and spindle. */
export function ServicePanel() {
  const st = status.value;
  const view = useServiceAxes();
  const by = new Map((view?.axes ?? []).map((s) => [s.name, s]));
  return (
    <Panel title="Service axes" id="service">
      {!st || !online.value ? <p class="hint">No status yet.</p> : null}
      <div class="svc-grid">
        {(st?.axes ?? []).map((a) => (
          <AxisCard key={a.name} a={a} s={by.get(a.name)} />
        ))}
      </div>
    </Panel>
  );
}
