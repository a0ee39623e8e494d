// The axis status signals of 003 §4.2 as a compact row of lamps: what the PLC sees of an axis.
import type { AxisStatus } from "../api/types";
import { Lamp } from "./Lamp";

/** HOMED, MVPOS, MVNEG, READY, INPOS for every axis; N_act=N_comm, N_act=0, GEAR1..3 for
 * spindles; the rotary-axis mode for a main spindle with rotary-axis capability. */
export function AxisSignalLamps({ a }: { a: AxisStatus }) {
  const s = a.signals;
  const id = (sig: string) => `sig-${a.name}-${sig}`;
  return (
    <div class="lamps signals" role="group" aria-label={`${a.display_name} status signals [003 §4.2]`}>
      <Lamp id={id("HOMED")} on={s.homed} label="HOMED" tone="info" title="the axis is homed" />
      <Lamp id={id("READY")} on={s.ready} label="READY" title="the drive follows: enables and ready status" />
      <Lamp id={id("INPOS")} on={s.inpos} label="INPOS" tone="info" title="in position" />
      <Lamp id={id("MVPOS")} on={s.mvpos} label="MVPOS" tone="info" title="moving in the positive direction" />
      <Lamp id={id("MVNEG")} on={s.mvneg} label="MVNEG" tone="info" title="moving in the negative direction" />
      {s.n_act_eq_n_comm != null ? (
        <Lamp id={id("N_NCMD")} on={s.n_act_eq_n_comm} label="N act = N comm" title="N_NCMD: the speed is reached" />
      ) : null}
      {s.n_act_zero != null ? (
        <Lamp id={id("N_NMIN")} on={s.n_act_zero} label="N act = 0" tone="info" title="N_NMIN: standstill" />
      ) : null}
      {s.gear_bits?.map((on, i) => (
        <Lamp key={i} id={id(`GEAR${i + 1}`)} on={on} label={`GEAR${i + 1}`} tone="info"
          title="the gear stage in binary, GEAR1 first" />
      ))}
      {s.rotary_mode != null ? (
        <Lamp id={id("ROTARY")} on={s.rotary_mode} label="rotary mode" tone="info"
          title="rotary axis mode (on) or spindle mode (off)" />
      ) : null}
    </div>
  );
}
