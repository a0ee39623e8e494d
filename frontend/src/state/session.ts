// The session: which machine, its status (pushed over the telemetry socket, never polled), and
// the one way commands are sent.
import { computed, signal } from "@preact/signals";
import { http, reachListeners } from "../api/http";
import type { AxisStatus, Command, CommandResult, MachineStatus, MachineSummary, NoticeMessage } from "../api/types";
import { loggedIn } from "./auth";

export type Connection = "connecting" | "online" | "lost";

export const machines = signal<MachineSummary[]>([]);
export const machineId = signal<string>("");
export const status = signal<MachineStatus | null>(null);
/** Notices to read, oldest first, each until dismissed: the machine rebuilt after its worker
 * died or restored from a snapshot, a message from the instructor, resumed by the instructor. */
export const notices = signal<NoticeMessage[]>([]);
/** The instructor froze this machine (a class seat): what the notice said ("" when known from
 * the exercise only); null while it is not frozen. */
export const frozen = signal<string | null>(null);
const MAX_NOTICES = 4;
let lastNoticeSeq = 0; // the socket sends the newest notice again when it reconnects
let freezeNotices = 0; // frozen/resumed notices so far: an exercise answer asked for before one is stale
/** The telemetry socket: it brings status, events and samples. */
export const socket = signal<Connection>("connecting");
/** Requests reach the service (false after one failed on the network, until one gets through). */
export const reachable = signal(true);
/** The pushed status stopped arriving although the socket looks open (a silent network). */
export const statusStale = signal(false);
export const connection = computed<Connection>(() => {
  if (socket.value === "lost" || !reachable.value || statusStale.value) return "lost";
  return socket.value === "online" && status.value ? "online" : "connecting";
});

const STALE_MS = 2000; // status comes about 20 times a second
const PROBE_MS = 1000;
let lastStatusMs = 0;

// Numbers are shown at most 10 times a second, as on a controller's own screen: each shown
// status re-renders every panel that reads it, and at the 20 pushes a second that cost the
// browser a fifth of a core. A status arriving after a quiet spell shows at once.
const SHOW_EVERY_MS = 100;
let shownMs = 0;
let newest: MachineStatus | null = null;
let showTimer = 0;

function show(): void {
  showTimer = 0;
  shownMs = Date.now();
  if (newest && newest.id === machineId.value) status.value = newerControl(newest, status.value);
  newest = null;
}

/** `st` with the newer of its and `shown`'s control: a push sent before a control action's answer
 * may arrive after it, and must not bring back the state the action ended. */
function newerControl(st: MachineStatus, shown: MachineStatus | null): MachineStatus {
  const own = shown?.id === st.id ? shown.control : null;
  return own && st.control && own.seq > st.control.seq ? { ...st, control: own } : st;
}

/** A status pushed for the current machine. */
export function statusArrived(st: MachineStatus): void {
  if (st.id !== machineId.value) return;
  newest = st;
  lastStatusMs = Date.now();
  statusStale.value = false;
  if (showTimer) return;
  const wait = shownMs + SHOW_EVERY_MS - lastStatusMs;
  if (wait <= 0) show();
  else showTimer = window.setTimeout(show, wait);
}

let probing = false;
reachListeners.add((reached) => {
  reachable.value = reached;
  if (reached || probing) return;
  probing = true; // ask until the service answers again (no other request may come meanwhile)
  const probe = async (): Promise<void> => {
    try {
      await http.get("/api/health");
      probing = false;
    } catch {
      setTimeout(() => void probe(), PROBE_MS);
    }
  };
  setTimeout(() => void probe(), PROBE_MS);
});
setInterval(() => {
  statusStale.value = socket.value === "online" && lastStatusMs > 0 && Date.now() - lastStatusMs > STALE_MS;
}, STALE_MS / 4);
export const online = computed(() => connection.value === "online");

/** A notice pushed for the current machine; false when it was seen already (a reconnect). */
export function noticeArrived(msg: NoticeMessage): boolean {
  if (msg.seq === lastNoticeSeq) return false;
  lastNoticeSeq = msg.seq;
  if (msg.kind === "frozen" || msg.kind === "resumed") freezeNotices++;
  if (msg.kind === "frozen") {
    frozen.value = `${msg.message} at ${new Date(msg.time_unix * 1000).toLocaleTimeString()}`;
    return true;
  }
  if (msg.kind === "resumed") frozen.value = null;
  notices.value = [...notices.value, msg].slice(-MAX_NOTICES);
  return true;
}

export function dismissNotice(seq: number): void {
  notices.value = notices.value.filter((n) => n.seq !== seq);
}

/** Freeze notices so far (ask before requesting the exercise, pass to `seatFrozen`). */
export const freezeNoticeCount = (): number => freezeNotices;

/** The exercise says whether the seat is frozen (a page opened while it was): believed unless
 * a freeze notice came while it was on its way. */
export function seatFrozen(isFrozen: boolean, askedAt: number): void {
  if (askedAt !== freezeNotices) return;
  if (!isFrozen) frozen.value = null;
  else if (frozen.value === null) frozen.value = "";
}

function forgetNotices(): void {
  notices.value = [];
  frozen.value = null;
  lastNoticeSeq = 0;
}

export const axis = (name: string) => status.value?.axes.find((a) => a.name === name) ?? null;

export type AxisOutline = Pick<AxisStatus, "name" | "kind" | "gear">;
let outlineKey = "";
let outlineNow: readonly AxisOutline[] = [];
/** The machine's axes by name, kind and gear in use, without their live values: a new value
 * only when these change, so a panel that lists the axes (the parameter table) renders again
 * when they change, not with every status push (20 a second). */
export const axisOutline = computed<readonly AxisOutline[]>(() => {
  const axes = status.value?.axes ?? [];
  const key = axes.map((a) => `${a.name}:${a.kind}:${a.gear}`).join(",");
  if (key !== outlineKey) {
    outlineKey = key;
    outlineNow = axes.map((a) => ({ name: a.name, kind: a.kind, gear: a.gear }));
  }
  return outlineNow;
});

/** A machine's route; throws while no machine is chosen (never `/api/machines//…`). */
export function machineUrl(path = ""): string {
  if (!machineId.value) throw new Error("no machine chosen yet");
  return `/api/machines/${encodeURIComponent(machineId.value)}${path}`;
}

/** Motion commands are refused in an emergency stop until reset: their buttons say so. */
export const motionLocked = computed(() => !online.value || !!status.value?.emergency_stop);

/** Load the machine list and choose the first machine unless `#machine` says (the socket
 * follows the chosen machine). Gives up when the user logs out meanwhile. */
export async function startSession(): Promise<void> {
  while (loggedIn.value) {
    try {
      const list = await http.get<MachineSummary[]>("/api/machines");
      if (!loggedIn.value) return; // logged out while the list was on its way
      machines.value = list;
      const wanted = decodeURIComponent(location.hash.slice(1)).split("/")[0];
      // a student's own seat first (the list also names a machine their instructor presents)
      const first = machines.value.find((m) => m.seat) ?? machines.value[0];
      machineId.value = machines.value.find((m) => m.id === wanted)?.id ?? first?.id ?? "";
      return;
    } catch {
      socket.value = "lost";
      await new Promise((r) => setTimeout(r, 1000));
    }
  }
}

/** The machine on screen may have gone (deleted, its class ended): read the list again and,
 * when it is not in it any more, show the first machine left instead of retrying it. */
export async function checkMachineStill(mid: string): Promise<void> {
  let list: MachineSummary[];
  try {
    list = await http.get<MachineSummary[]>("/api/machines");
  } catch {
    return; // the service is away: the socket keeps trying
  }
  machines.value = list;
  if (machineId.value === mid && !list.some((m) => m.id === mid)) selectMachine(list[0]?.id ?? "");
}

/** Logged out: no machine, so the socket closes and nothing asks the service any more
 * (`#machine` stays, the same machine shows after the next login). */
export function endSession(): void {
  machineId.value = "";
  machines.value = [];
  status.value = null;
  forgetNotices();
  lastStatusMs = 0;
  socket.value = "connecting";
}

export function selectMachine(id: string): void {
  machineId.value = id;
  status.value = null;
  forgetNotices();
  lastStatusMs = 0;
  location.hash = encodeURIComponent(id); // the workspace is added again (state/route.ts)
}

/** Emergency stop: needs no control, whoever may stop stops (api/auth.py STOP). */
export async function emergencyStop(): Promise<CommandResult> {
  return http.post<CommandResult>(machineUrl("/emergency-stop"), {});
}

/** Send one command; resolves to the acknowledgement, rejects with the refusal (ApiError). */
export async function send(cmd: Command): Promise<CommandResult> {
  return http.post<CommandResult>(machineUrl("/commands"), cmd);
}
