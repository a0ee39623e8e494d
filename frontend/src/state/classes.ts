// The instructor's side of classes: which screen shows (the machine HMI or the console, kept
// in the URL as `#classes`), the classes and exercises, and the open class's grid: pushed
// frames over the grid websocket (a one-time ticket first, as the telemetry socket), each
// seat's newest frame in a signal of its own and its lag/speed history for the sparklines.
// Only a seat's own tile re-renders when its frame changes; the tiles themselves stay.
import { batch, computed, effect, signal, type Signal } from "@preact/signals";
import { http } from "../api/http";
import type {
  ClassCreate,
  ClassCreated,
  ClassInfo,
  ExerciseInfo,
  FaultInfo,
  FaultInject,
  GridFrame,
  SeatFaults,
  SeatFrame,
  SeatLink,
  WsTicket,
} from "../api/types";
import { loggedIn } from "./auth";
import { may } from "./control";
import { machineId, machines, selectMachine } from "./session";
import type { MachineSummary } from "../api/types";

export type View = "hmi" | "classes";
const CONSOLE_HASH = "#classes";

/** The console (instructors: `may("teach")`) or the machine HMI. */
export const view = signal<View>(location.hash.startsWith(CONSOLE_HASH) ? "classes" : "hmi");

/** Show the console; the URL keeps it (a reload opens it again). */
export function openConsole(): void {
  view.value = "classes";
  history.replaceState(null, "", CONSOLE_HASH + (openClass.value ? `/${openClass.value}` : ""));
}

/** Back to the machine HMI, on `machine` when given (a seat's live view). The machine list
 * is read again: a class made since has new machines. */
export async function openHmi(machine?: string): Promise<void> {
  const list = await http.get<MachineSummary[]>("/api/machines");
  machines.value = list;
  if (machine) {
    selectMachine(machine);
  } else {
    history.replaceState(null, "", location.pathname);
    // the machine shown before may have gone with a class that ended meanwhile
    if (!list.some((m) => m.id === machineId.value)) selectMachine(list[0]?.id ?? "");
  }
  view.value = "hmi";
}

// --- classes and exercises --------------------------------------------------------------
export const classes = signal<ClassInfo[]>([]);
export const exercises = signal<ExerciseInfo[]>([]);
/** The class whose grid (or, ended, whose debrief) shows. */
export const openClass = signal<string>(location.hash.match(/^#classes\/([a-z0-9-]+)/)?.[1] ?? "");

export async function loadClasses(): Promise<void> {
  classes.value = await http.get<ClassInfo[]>("/api/classes");
}

export async function loadExercises(): Promise<void> {
  exercises.value = await http.get<ExerciseInfo[]>("/api/exercises");
}

/** Forget an ended class (its id can be used again); the console shows none then. */
export async function deleteClass(cid: string): Promise<void> {
  await http.del<void>(`/api/classes/${cid}`);
  chooseClass("");
  await loadClasses();
}

export function chooseClass(cid: string): void {
  openClass.value = cid;
  selected.value = new Set();
  history.replaceState(null, "", CONSOLE_HASH + (cid ? `/${cid}` : ""));
}

/** A new class; its seats' login links come with the answer, this once. */
export async function createClass(req: ClassCreate): Promise<ClassCreated> {
  const created = await http.post<ClassCreated>("/api/classes", req);
  await loadClasses();
  return created;
}

export async function endClass(cid: string): Promise<void> {
  await http.post<ClassInfo>(`/api/classes/${cid}/end`, {});
  await loadClasses();
}

/** A new one-time login link of a seat (the old one stops working once used, or in an hour). */
export const newLink = (cid: string, n: number) => http.post<SeatLink>(`/api/classes/${cid}/seats/${n}/link`, {});

// --- actions on seats (an empty list: the whole class) -------------------------------------
/** The seats ticked in the grid. */
export const selected = signal<Set<number>>(new Set());

export function toggleSeat(n: number): void {
  const s = new Set(selected.value);
  if (s.has(n)) s.delete(n);
  else s.add(n);
  selected.value = s;
}

export const freeze = (cid: string, seats: number[], frozen: boolean) =>
  http.post<ClassInfo>(`/api/classes/${cid}/freeze`, { seats, frozen });
/** A class as an action's answer has it, in place of the one listed. */
const took = (info: ClassInfo) => void (classes.value = classes.value.map((c) => (c.id === info.id ? info : c)));
/** Show a machine to every seat, read-only (null: stop). */
export const present = (cid: string, machine: string | null) =>
  http.post<ClassInfo>(`/api/classes/${cid}/present`, { machine }).then(took);
/** The seats (all for none) on to the lesson plan's next exercise. */
export const moveSeatsOn = (cid: string, seats: number[]) => http.post<ClassInfo>(`/api/classes/${cid}/next`, { seats }).then(took);
export const broadcast = (cid: string, seats: number[], text: string) =>
  http.post<null>(`/api/classes/${cid}/broadcast`, { seats, text });
/** An instructor lowers a seat's raised hand (seen to). */
export const lowerHand = (mid: string) => http.post<null>(`/api/machines/${mid}/exercise/hand`, { raised: false, text: "" });
export const injectSeat = (mid: string, inject: FaultInject) => http.post<FaultInfo>(`/api/machines/${mid}/faults`, inject);
export const injectClass = (cid: string, seats: number[], inject: FaultInject) =>
  http.post<SeatFaults[]>(`/api/classes/${cid}/faults`, { seats, inject });

// --- the grid -----------------------------------------------------------------------------
export const HISTORY_S = 60; // the sparklines' window
const CAPACITY = 512; // frames kept: 60 s at 4 Hz and room to spare

/** One sparkline's samples: the grid's wall time and a value (the peak lag or speed since the
 * previous frame, so a spike between frames shows), a ring. */
export class Series {
  readonly t = new Float64Array(CAPACITY);
  readonly v = new Float64Array(CAPACITY);
  head = 0; // next slot
  size = 0;
  push(t: number, v: number): void {
    this.t[this.head] = t;
    this.v[this.head] = v;
    this.head = (this.head + 1) % CAPACITY;
    this.size = Math.min(this.size + 1, CAPACITY);
  }
  /** Oldest first, k = 0 .. size-1. */
  at(k: number): number {
    return (this.head - this.size + k + CAPACITY) % CAPACITY;
  }
}

/** A seat in the open grid: its newest frame and, per axis line, its history. */
export interface SeatLive {
  n: number;
  frame: Signal<SeatFrame>;
  history: Map<string, Series>;
}

export type GridLink = "closed" | "connecting" | "online" | "lost";
export const gridLink = signal<GridLink>("closed");
/** Seats of the open class, in seat order; the array is replaced only when the seats do. */
export const seats = signal<SeatLive[]>([]);
/** Wall time of the newest frame (the sparklines' right edge). */
export const gridTime = signal(0);

function take(frame: GridFrame): void {
  batch(() => {
    let live = seats.value;
    if (live.length !== frame.seats.length || live.some((s, i) => s.n !== frame.seats[i].n)) {
      live = frame.seats.map((f) => ({ n: f.n, frame: signal(f), history: new Map<string, Series>() }));
      seats.value = live;
    }
    frame.seats.forEach((f, i) => {
      const s = live[i];
      for (const a of f.axes) {
        let series = s.history.get(a.name);
        if (!series) s.history.set(a.name, (series = new Series()));
        series.push(frame.t_unix, a.kind === "spindle" ? a.speed_peak : a.lag_peak);
      }
      s.frame.value = f;
    });
    gridTime.value = frame.t_unix;
  });
}

const RECONNECT_MS = 1000;
const NOT_FOUND = 4404;
let ws: WebSocket | null = null;
let attempt = 0;
let wasLost = false; // the grid's socket broke: its next frame reads the classes again

async function connect(cid: string): Promise<void> {
  const mine = ++attempt;
  gridLink.value = "connecting";
  let ticket: WsTicket;
  try {
    ticket = await http.post<WsTicket>("/api/auth/ws-ticket", {});
  } catch {
    if (mine === attempt) setTimeout(() => mine === attempt && void connect(cid), RECONNECT_MS);
    return;
  }
  if (mine !== attempt) return;
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const sock = new WebSocket(`${proto}://${location.host}/api/classes/${cid}/grid?ticket=${encodeURIComponent(ticket.ticket)}`);
  ws = sock;
  sock.onmessage = (ev) => {
    const back = wasLost; // the service may have restarted meanwhile
    wasLost = false;
    gridLink.value = "online";
    const frame = JSON.parse(ev.data as string) as GridFrame;
    // ended elsewhere, or back after a restart: the class list says what changed (an ended
    // class closes its grid and shows its debrief)
    if (frame.ended || back) void loadClasses().catch(() => undefined);
    if (!frame.ended) take(frame);
  };
  sock.onclose = (ev) => {
    if (ws !== sock) return; // replaced on purpose
    ws = null;
    gridLink.value = "lost";
    wasLost = true;
    if (ev.code !== NOT_FOUND) setTimeout(() => mine === attempt && void connect(cid), RECONNECT_MS);
  };
}

/** The class whose grid socket is open: the console shows it and it runs. */
const gridClass = computed(() => {
  const cid = openClass.value;
  const running = classes.value.some((c) => c.id === cid && c.ended_unix === null);
  return loggedIn.value && view.value === "classes" && may("teach") && running ? cid : "";
});

let seatsOf = ""; // the class the seats' tiles and sparklines belong to

effect(() => {
  const wanted = gridClass.value;
  const old = ws;
  ws = null;
  old?.close();
  attempt++;
  gridLink.value = "closed";
  // back from a seat's live view to the same class: its tiles keep their last minute
  if (wanted && wanted !== seatsOf) {
    seats.value = [];
    seatsOf = wanted;
  }
  if (wanted) void connect(wanted);
});
