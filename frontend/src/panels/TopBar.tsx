// Always visible: machine, time and loop health, connection, who is logged in, and the emergency
// stop. The instructor console shows no machine: there the bar has the brand, the view switch
// and the user only (`machine={false}`).
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { Refusal } from "../api/types";
import { logout, me } from "../state/auth";
import { may } from "../state/control";
import { openConsole, openHmi, view } from "../state/classes";
import { seatStudent } from "../state/exercise";
import { connection, emergencyStop, machineId, machines, online, selectMachine, status } from "../state/session";
import { machinesOpen } from "../state/machines";
import { AccountDialog, accountOpen } from "./Account";
import { Lamp } from "../ui/Lamp";
import { fmt, qty } from "../ui/format";
import { RefusalLine, useCommand } from "../ui/useCommand";

// (wall time ms, overruns so far) of the last minute's statuses: the rate the bar shows
const overrunSeen: [number, number][] = [];

/** Overruns in the last minute (the count since the worker started is in the title). */
function overrunRate(total: number | undefined): string {
  if (total === undefined) return "—";
  const now = Date.now();
  const last = overrunSeen[overrunSeen.length - 1];
  if (last && total < last[1]) overrunSeen.length = 0; // another worker or machine: start again
  if (!last || last[1] !== total || now - last[0] > 1000) overrunSeen.push([now, total]);
  while (overrunSeen.length > 1 && now - overrunSeen[0][0] > 60_000) overrunSeen.shift();
  return String(total - overrunSeen[0][1]);
}

export function TopBar({ machine = true }: { machine?: boolean }) {
  const s = status.value;
  const sim = s?.simulation;
  const c = connection.value;
  const estop = useCommand();
  return (
    <header class="topbar">
      <span class="brand wide-only">Inbetrieb</span>
      {may("teach") ? <ViewSwitch /> : null}
      {machine ? (
        <>
          <label class="machine-select">
            <span class="wide-only">Machine </span>
            <select aria-label="Machine" value={machineId.value} onChange={(e) => selectMachine((e.target as HTMLSelectElement).value)}>
              {machines.value.map((m) => (
                <option value={m.id} key={m.id}>
                  {m.name}
                </option>
              ))}
            </select>
          </label>
          {me.value?.guest ? null : (
            <button type="button" class="secondary" data-testid="open-machines" title="pacing, restart, new and deleted machines"
              onClick={() => (machinesOpen.value = true)}>
              Machines…
            </button>
          )}
          <span class="health" data-testid="health">
            {/* fixed-width cells (styles.css .health): growing numbers do not move the bar;
                on a small screen the loop's p99 is in the title only */}
            <span class="h-time" title="simulated time">t = {qty(sim?.t_s, 2, "s")}</span>
            <span class="h-pace" title="simulated seconds per wall second">
              {sim?.mode ?? "—"} ×{fmt(sim?.rt_factor, 2)}
            </span>
            <span
              class="h-loop"
              title={
                `real-time loop of worker ${sim?.worker ?? "—"}: an overrun is a tick whose work ran past the next ` +
                "deadline (the machine's time waited a moment; the simulation itself stays exact). A few a minute are " +
                `harmless; many mean the computer is too busy. ${sim?.loop_overruns ?? 0} since the worker started; ` +
                `work per tick, 99th percentile ${qty(sim?.loop_work_p99_ms, 2, "ms")}`
              }
              data-testid="loop-health"
            >
              <span class="wide-only">loop </span>{sim?.worker ?? "—"} ·{" "}
              <span data-testid="overrun-rate">{overrunRate(sim?.loop_overruns)}</span>
              <span class="wide-only"> overruns</span>/min
              <span class="wide-only"> · p99 {qty(sim?.loop_work_p99_ms, 2, "ms")}</span>
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
        </>
      ) : null}
      {/* one group: when the bar wraps, the emergency stop stays at the right end */}
      <span class="topbar-end">
        <UserBox />
        {machine ? (
          <button
            class="estop"
            data-testid="estop"
            disabled={!online.value || !may("stop")}
            onClick={() => void estop.run(emergencyStop)}
            title={may("stop") ? "Emergency stop: every axis brakes with a_emergency (no control needed)" : `a user in the role ${me.value?.role ?? ""} may not stop the machine`}
          >
            EMERGENCY STOP
          </button>
        ) : null}
      </span>
    </header>
  );
}

/** Instructors switch between the machine HMI and the class console (state/classes.ts). */
function ViewSwitch() {
  return view.value === "classes" ? (
    <button type="button" class="secondary" data-testid="back-to-hmi" onClick={() => void openHmi()}>◂ Machine HMI</button>
  ) : (
    <button type="button" class="secondary" data-testid="open-classes" onClick={openConsole}>Classes</button>
  );
}

/** A link's expiry, short: the time today, else the day and time. */
function until(t_unix: number): string {
  const d = new Date(t_unix * 1000);
  const today = d.toDateString() === new Date().toDateString();
  return today
    ? d.toLocaleTimeString([], { hour: "2-digit", minute: "2-digit" })
    : d.toLocaleString([], { month: "short", day: "numeric", hour: "2-digit", minute: "2-digit" });
}

/** Who is logged in, in which role, and the way out. */
function UserBox() {
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const user = me.value;
  if (!user) return null;
  const leave = () =>
    logout().catch((e: unknown) =>
      setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
  const share = user.share;
  if (share) {
    // a guest has no account: what they watch, through which link, until when
    return (
      <span class="user guest" data-testid="guest-box">
        <span data-testid="guest-link" title={`watching ${share.machine} through a share link${share.label ? ` (${share.label})` : ""} until ${new Date(share.expires_unix * 1000).toLocaleString()}`}>
          shared{share.label ? <> · <b>{share.label}</b></> : null} · until {until(share.expires_unix)}
        </span>
        <RefusalLine refusal={refusal} id="logout-error" />
        <button type="button" class="secondary" data-testid="logout" onClick={() => void leave()}>
          Leave
        </button>
      </span>
    );
  }
  return (
    <span class="user" title="logged in as">
      <RefusalLine refusal={refusal} id="logout-error" />
      <button type="button" class="secondary account-open" data-testid="account-open" title={`your account (${user.role}): API tokens (and users)`}
        onClick={() => (accountOpen.value = true)}>
        {/* a class seat's student by their name, not the seat's login */}
        <b data-testid="user-name" title={user.name}>
          {seatStudent.value?.user === user.name ? `${seatStudent.value.student} (seat ${seatStudent.value.seat})` : user.name}
        </b>{" "}
        <span data-testid="user-role" class="wide-only">{user.role}</span>
      </button>
      <button type="button" class="secondary" data-testid="logout" onClick={() => void leave()}>
        Log out
      </button>
      <AccountDialog />
    </span>
  );
}
