// Layout: the login screen while nobody is logged in; then the top bar (machine, health,
// connection, user, emergency stop) and banners always, the machine view beside the workspaces (tabs).
import { useEffect, useRef } from "preact/hooks";
import { AuditPanel } from "./panels/AuditPanel";
import { BundlePage } from "./panels/BundlePage";
import { BundlesPanel } from "./panels/BundlesPanel";
import { FleetPanel } from "./panels/FleetPanel";
import { HistoryPanel } from "./panels/HistoryPanel";
import { SharePanel } from "./panels/SharePanel";
import { Banner } from "./panels/Banner";
import { Calculators } from "./panels/Calculators";
import { Commissioning } from "./panels/Commissioning";
import { ControlStrip } from "./panels/ControlStrip";
import { EstopHint } from "./panels/EstopHint";
import { ExercisePanel } from "./panels/ExercisePanel";
import { HliPanel } from "./panels/HliPanel";
import { JogPanel } from "./panels/JogPanel";
import { Login } from "./panels/Login";
import { MachineView } from "./panels/MachineView";
import { MachinesDialog } from "./panels/MachinesDialog";
import { MdiPanel } from "./panels/MdiPanel";
import { PendingStrip } from "./panels/PendingStrip";
import { watching } from "./state/presenting";
import { PresentStrip } from "./panels/PresentStrip";
import { Parameters } from "./panels/Parameters";
import { Plots } from "./panels/Plots";
import { ProgramPanel } from "./panels/ProgramPanel";
import { ReportPanel } from "./panels/ReportPanel";
import { Scope } from "./panels/Scope";
import { ServicePanel } from "./panels/ServicePanel";
import { SpindlePanel } from "./panels/SpindlePanel";
import { TopBar } from "./panels/TopBar";
import { TrialBar } from "./panels/TrialBar";
import { Console } from "./console/Console";
import { view } from "./state/classes";
import { me } from "./state/auth";
import { commandBlocked, may } from "./state/control";
import { exercise } from "./state/exercise";
import { machinesOpen } from "./state/machines";
import { bundlePage, TABS, type Tab, tab as routeTab } from "./state/route";
import { connection, frozen, online, status } from "./state/session";
import { RefusalLine, useCommand } from "./ui/useCommand";

// "Exercise" only on a class seat (the first tab there, and the one it opens on); a share
// link's guest watches: the live machine, its parameters, traces and history
const GUEST_TABS = new Set<Tab>(["Operate", "Plots", "Scope", "Parameters", "History"]);

/** The CNC reset and, on a frozen seat, why the simulation stands (pacing, restart and the
 * machines themselves: the Machines dialog). */
function MachineControls() {
  const cmd = useCommand();
  const blocked = commandBlocked.value; // another holder, or a role that may not command
  return (
    <div class="controls-apart" aria-label="reset and simulation">
      <button type="button" class="secondary" data-testid="reset" disabled={!online.value || !!blocked}
        onClick={() => void cmd.run({ type: "reset" })} title={blocked || "CNC reset: clears job errors and the block queue, stops motion"}>
        ⟲ Reset
      </button>
      <EstopHint />
      {me.value?.guest ? null : (
        <button type="button" class="secondary" data-testid="open-machines-side" onClick={() => (machinesOpen.value = true)}
          title="run, pause, step, fast; restart; machines">
          Simulation: {status.value?.simulation.mode ?? "—"} …
        </button>
      )}
      {frozen.value !== null ? <span class="pace-reason" data-testid="pace-reason">Frozen by the instructor</span> : null}
      <RefusalLine refusal={cmd.refusal} />
    </div>
  );
}

const tabId = (t: Tab) => `ws-tab-${t.replace(/\W+/g, "-")}`;

/** The workspaces as WAI-ARIA tabs: one tab stop (the selected tab), arrow keys, Home and End
 * move between them and select (automatic activation), Enter and Space as for any button. */
function Tabs({ tabs, tab, setTab }: { tabs: readonly Tab[]; tab: Tab; setTab: (t: Tab) => void }) {
  const onKey = (e: KeyboardEvent) => {
    const i = tabs.indexOf(tab);
    const to = { ArrowRight: i + 1, ArrowLeft: i - 1, Home: 0, End: tabs.length - 1 }[e.key];
    if (to === undefined) return;
    e.preventDefault();
    const next = tabs[(to + tabs.length) % tabs.length];
    setTab(next);
    document.getElementById(tabId(next))?.focus();
  };
  return (
    <nav class="tabs" role="tablist" aria-label="workspaces" onKeyDown={onKey}>
      {tabs.map((t) => (
        <button key={t} type="button" role="tab" id={tabId(t)} aria-selected={t === tab} aria-controls="workspace"
          tabIndex={t === tab ? 0 : -1} data-testid={`tab-${t}`} class={t === tab ? "active" : ""} onClick={() => setTab(t)}>
          {t}
        </button>
      ))}
    </nav>
  );
}

export function App() {
  if (me.value === undefined) return <p class="hint login-wait">Connecting to the service…</p>;
  if (!me.value) return <Login />;
  if (bundlePage.value && !me.value.guest) return <BundlePage />;
  if (view.value === "classes" && may("teach")) return <ConsoleScreen />;
  return <Hmi />;
}

/** The instructor console under the top bar (state/classes.ts `view`): no machine is shown,
 * so the bar has no machine select, health or emergency stop. */
function ConsoleScreen() {
  return (
    <div class="app">
      <div class="head">
        <TopBar machine={false} />
      </div>
      <MachinesDialog />
      <Console />
    </div>
  );
}

function Hmi() {
  const guest = !!me.value?.guest || watching.value; // a presentation is watched as a guest would
  const tab = guest && !GUEST_TABS.has(routeTab.value) ? "Operate" : routeTab.value;
  const setTab = (t: Tab) => (routeTab.value = t);
  const seat = !!exercise.value;
  useEffect(() => {
    const t = routeTab.value;
    routeTab.value = seat ? "Exercise" : t === "Exercise" ? "Operate" : t;
  }, [seat]);
  const head = useRef<HTMLDivElement>(null);
  const side = useRef<HTMLElement>(null);
  useEffect(() => {
    // focus and scrollIntoView keep controls clear of the sticky head (its height varies:
    // banners come and go) and, on a small screen, of the machine view stuck under it
    const h = head.current;
    const s = side.current;
    if (!h || !s) return;
    const root = document.documentElement.style;
    const ro = new ResizeObserver(() => {
      root.setProperty("--head-h", `${h.offsetHeight}px`);
      root.setProperty("--side-h", `${s.offsetHeight}px`);
    });
    ro.observe(h);
    ro.observe(s);
    return () => ro.disconnect();
  }, []);
  return (
    <div class={connection.value === "lost" ? "app stale" : "app"}>
      {/* top bar, banners and the trial bar stay on screen while the page scrolls; they take
          their own space (sticky, not fixed), and scrolling to a control keeps it below them */}
      <div class="head" ref={head}>
        <TopBar />
        <PresentStrip />
        <ControlStrip />
        <PendingStrip />
        <Banner liveRun={tab !== "Commissioning" && tab !== "Drive tuning"} />
        <TrialBar />
      </div>
      <MachinesDialog />
      <div class="body">
        <aside class="side" ref={side} aria-label="machine state">
          <MachineView />
          <MachineControls />
        </aside>
        <main class="main">
          <Tabs tabs={TABS.filter((t) => (seat || t !== "Exercise") && (!guest || GUEST_TABS.has(t)))} tab={tab} setTab={setTab} />
          <div class="workspace" role="tabpanel" id="workspace" aria-labelledby={tabId(tab)}>
            {tab === "Exercise" ? <ExercisePanel /> : null}
            {tab === "Operate" ? (
              <div class="operate">
                <SpindlePanel />
                <JogPanel />
                <MdiPanel />
                <Plots single />
              </div>
            ) : null}
            {tab === "Program" ? <ProgramPanel /> : null}
            {tab === "Plots" ? <Plots /> : null}
            {tab === "Scope" ? <Scope /> : null}
            {tab === "Parameters" ? <Parameters /> : null}
            {tab === "Commissioning" ? (
              <>
                <Commissioning />
                <Calculators />
                <ReportPanel />
              </>
            ) : null}
            {tab === "Drive tuning" ? <Commissioning drive /> : null}
            {tab === "Service" ? <ServicePanel /> : null}
            {tab === "HLI / PLC" ? <HliPanel /> : null}
            {tab === "History" ? (
              <>
                <HistoryPanel />
                {may("share") ? <SharePanel /> : null}
                {me.value?.guest ? null : <BundlesPanel />}
                {may("users") ? <AuditPanel /> : null}
              </>
            ) : null}
            {tab === "Fleet" ? <FleetPanel /> : null}
          </div>
        </main>
      </div>
    </div>
  );
}
