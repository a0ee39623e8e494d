// Machines, the one place to manage them (opened from the machine select in the top bar): the
// pacing of the machine on screen (run, pause, step, fast), its restart with the values that
// wait for it, every machine with a delete, and a new machine (NewMachine.tsx). Each control
// says why when the user's role or control of the machine does not allow it.
import { useEffect, useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { me } from "../state/auth";
import { may } from "../state/control";
import { deleteMachine, machinesOpen, pace, pendingRestart, type PendingRestart, refreshMachines, stepCycles } from "../state/machines";
import { paramsVersion } from "../state/params";
import { frozen, machineId, machines, online, selectMachine, status } from "../state/session";
import { Panel } from "../ui/Panel";
import { fmt, qty } from "../ui/format";
import { RefusalLine } from "../ui/useCommand";
import { NewMachine } from "./NewMachine";
import { RestartMachine } from "./RestartMachine";

const refusalOf = (e: unknown): Refusal => (e instanceof ApiError ? e.refusal : { message: String(e), problems: [] });

/** Run a request, keep its refusal (null on success). */
function useRequest() {
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const run = async (work: () => Promise<unknown>): Promise<boolean> => {
    try {
      await work();
      setRefusal(null);
      return true;
    } catch (e) {
      setRefusal(refusalOf(e));
      return false;
    }
  };
  return { run, refusal };
}

export function MachinesDialog() {
  useEffect(() => {
    if (machinesOpen.value) void refreshMachines().catch(() => undefined);
  }, [machinesOpen.value]);
  if (!machinesOpen.value) return null;
  const close = () => (machinesOpen.value = false);
  return (
    <div class="account-backdrop" onClick={(e) => e.target === e.currentTarget && close()}
      onKeyDown={(e) => e.key === "Escape" && close()}>
      <div class="account-dialog" role="dialog" aria-modal="true" aria-label="Machines">
        <Panel title="Machines" id="machines"
          actions={<button type="button" class="secondary" data-testid="machines-close" onClick={close}>Close</button>}>
          {machineId.value ? <ThisMachine /> : null}
          <MachineList />
          <NewMachine />
        </Panel>
      </div>
    </div>
  );
}

/** Pacing and restart of the machine on screen. */
function ThisMachine() {
  const s = status.value;
  const req = useRequest();
  const [cycles, setCycles] = useState("100");
  const [pending, setPending] = useState<PendingRestart[] | null>(null);
  useEffect(() => {
    setPending(null);
    void pendingRestart().then(setPending, () => setPending(null));
  }, [machineId.value, paramsVersion.value]); // a new build (a restart) bumps paramsVersion
  const mode = s?.simulation.mode;
  // pacing is the instructor's (api/auth.py SIMULATE), holding control or not
  const paceWhy = may("simulate")
    ? ""
    : frozen.value !== null
      ? "frozen by the instructor: only the instructor can resume the simulation"
      : `a user in the role ${me.value?.role ?? ""} may not pace the simulation`;
  const n = Number(cycles);
  const stepOk = Number.isInteger(n) && n >= 1 && n <= 1_000_000;
  const dis = !online.value;
  const paceButton = (m: "run" | "pause" | "fast", label: string, title: string) => (
    <button type="button" class="secondary" data-testid={`pace-${m}`} aria-pressed={mode === m} disabled={dis || mode === m || !!paceWhy}
      title={paceWhy || title} onClick={() => void req.run(() => pace(m))}>
      {label}
    </button>
  );
  return (
    <section class="account-section" aria-label="simulation pacing" data-testid="machine-pacing">
      <h3>
        This machine: {s?.name ?? machineId.value} <span class="hint">t = {qty(s?.simulation.t_s, 3, "s")} · cycle {s?.simulation.cycle ?? "—"} · {mode ?? "—"} ×{fmt(s?.simulation.rt_factor, 2)}</span>
      </h3>
      <div class="row">
        <span class="hint">Simulation</span>
        {paceButton("run", "▶ run", "in real time")}
        {paceButton("pause", "❚❚ pause", "hold the simulated time")}
        {paceButton("fast", "» fast", "as fast as the worker can (no real-time pacing)")}
        <label>
          step <input size={8} inputMode="numeric" value={cycles} data-testid="step-cycles" aria-invalid={!stepOk}
            onInput={(e) => setCycles((e.target as HTMLInputElement).value)} /> cycles
        </label>
        <button type="button" class="secondary" data-testid="pace-step" disabled={dis || !stepOk || !!paceWhy}
          title={paceWhy || (stepOk ? "pause, then advance this many cycles" : "a whole number of cycles, 1 … 1 000 000")}
          onClick={() => void req.run(() => stepCycles(n))}>
          ▸| step
        </button>
        {paceWhy && frozen.value !== null ? <span class="pace-reason" data-testid="pace-reason">Frozen by the instructor</span> : null}
      </div>
      <div class="row">
        <RestartMachine refusalId="restart-refusal" />
        <span class="hint" data-testid="restart-pending-count">
          {pending === null ? "" : pending.length ? `${pending.length} value(s) wait for the restart:` : "no value waits for a restart"}
        </span>
      </div>
      {pending?.length ? (
        <ul class="restart-pending" data-testid="restart-pending">
          {pending.map(({ list, value: p }) => (
            <li key={`${list}-${p.name}`}>
              {list}: <b>{p.name}</b> ({p.id}) {String(p.value)} → <b>{String(p.pending)}</b> {p.unit}
            </li>
          ))}
        </ul>
      ) : null}
      <RefusalLine refusal={req.refusal} id="machine-refusal" />
    </section>
  );
}

/** Every machine the user sees: open one, delete one (with a confirm). */
function MachineList() {
  const req = useRequest();
  const [doomed, setDoomed] = useState("");
  const [deleted, setDeleted] = useState("");
  const delWhy = may("machines") ? "" : `a user in the role ${me.value?.role ?? ""} may not delete machines`;
  return (
    <section class="account-section" aria-label="all machines">
      <h3>All machines</h3>
      <table class="account-table" data-testid="machine-list">
        <thead>
          <tr>
            <th>ID</th>
            <th>Name</th>
            <th>From</th>
            <th>Axes</th>
            <th>Simulation</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {machines.value.map((m) => (
            <tr key={m.id} data-testid={`machine-row-${m.id}`}>
              <td>{m.id}{m.id === machineId.value ? <span class="hint"> (on screen)</span> : null}</td>
              <td>{m.name}</td>
              <td>{m.source}</td>
              <td>{m.axes.join(", ")}</td>
              <td>{m.mode}</td>
              <td class="row">
                {m.id !== machineId.value ? (
                  <button type="button" class="secondary" onClick={() => selectMachine(m.id)}>Open</button>
                ) : null}
                {doomed === m.id ? (
                  <>
                    <button type="button" class="danger" data-testid={`machine-delete-confirm-${m.id}`}
                      onClick={() =>
                        void req.run(() => deleteMachine(m.id)).then((ok) => {
                          setDoomed("");
                          if (ok) setDeleted(`Deleted ${m.id} (${m.name}) at ${new Date().toLocaleTimeString()}.`);
                        })
                      }>
                      Delete {m.id} for good
                    </button>
                    <button type="button" class="secondary" onClick={() => setDoomed("")}>Cancel</button>
                  </>
                ) : (
                  <button type="button" class="secondary" data-testid={`machine-delete-${m.id}`} disabled={!!delWhy} title={delWhy}
                    onClick={() => (setDeleted(""), setDoomed(m.id))}>
                    Delete…
                  </button>
                )}
              </td>
            </tr>
          ))}
        </tbody>
      </table>
      {deleted ? <p class="hint" role="status" data-testid="machine-deleted">{deleted}</p> : null}
      <RefusalLine refusal={req.refusal} id="machine-list-refusal" />
    </section>
  );
}
