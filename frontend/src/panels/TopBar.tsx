// Always visible: machine, time and loop health, connection, and the emergency stop.
import { connection, machineId, machines, online, selectMachine, status } from "../state/session";
import { Lamp } from "../ui/Lamp";
import { fmt, qty } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";

export function TopBar() {
  const s = status.value;
  const sim = s?.simulation;
  const c = connection.value;
  const estop = useCommand();
  return (
    <header class="topbar">
      <span class="brand">Inbetrieb</span>
      <label class="machine-select">
        Machine{" "}
        <select value={machineId.value} onChange={(e) => selectMachine((e.target as HTMLSelectElement).value)}>
          {machines.value.map((m) => (
            <option value={m.id} key={m.id}>
              {m.name}
            </option>
          ))}
        </select>
      </label>
      <span class="health" data-testid="health">
        <span title="simulated time">t = {qty(sim?.t_s, 2, "s")}</span>
        <span title="simulated seconds per wall second">
          {sim?.mode ?? "—"} ×{fmt(sim?.rt_factor, 2)}
        </span>
        <span
          title={`real-time loop of worker ${sim?.worker ?? "—"}: ticks whose work ran past the next deadline; work per tick, 99th percentile`}
          data-testid="loop-health"
        >
          loop {sim?.worker ?? "—"} · overruns {sim?.loop_overruns ?? "—"} · p99 {qty(sim?.loop_work_p99_ms, 2, "ms")}
        </span>
      </span>
      <Lamp
        id="lamp-connection"
        on={c === "online"}
        tone="ok"
        label={c === "online" ? "connected" : c === "lost" ? "connection lost" : "connecting"}
      />
      {s?.emergency_stop ? <span class="estop-state">EMERGENCY STOP ACTIVE</span> : null}
      <RefusalLine refusal={estop.refusal} />
      <button
        class="estop"
        data-testid="estop"
        disabled={!online.value}
        onClick={() => void estop.run({ type: "emergency_stop" })}
        title="Emergency stop: every axis brakes with a_emergency"
      >
        EMERGENCY STOP
      </button>
    </header>
  );
}
