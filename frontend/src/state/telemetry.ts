// The telemetry websocket: the hello's signal catalogue, one subscription (the union of what
// the plots want), binary frames decoded into the rings, events into the log, the machine's
// pushed status and notices. Reconnects by
// itself; while it is down the session counts as lost (jog keys release on that). It opens only
// while a machine is chosen, i.e. while someone is logged in: each connect first fetches a
// one-time ticket with the session (the service refuses a socket with the cookie alone), and
// the service closes the socket (4401) when the session ends.
import { effect, signal } from "@preact/signals";
import type {
  ErrorMessage,
  EventMessage,
  FrameHeader,
  Hello,
  HistoryMessage,
  NoticeMessage,
  SignalInfo,
  StatusMessage,
  Subscribed,
  WsTicket,
} from "../api/types";
import { clientId, http } from "../api/http";
import { loadMe } from "./auth";
import { addEvents, restartLog } from "./events";
import { addHistory } from "./history";
import { dropTrialOf } from "./params";
import { presentationChanged } from "./presenting";
import { Rings } from "./rings";
import { checkMachineStill, machineId, noticeArrived, socket, statusArrived } from "./session";

const MAGIC = 0x54424e49; // "INBT" little-endian
export const RING_SECONDS = 30;
const RECONNECT_MS = 1000;
const SESSION_ENDED = 4401; // close code: the session or token behind the socket ended

export const catalogue = signal<SignalInfo[]>([]);
/** Rings of the current subscription (replaced when the subscription changes). */
export const rings = signal<Rings>(new Rings([], 1));
export const frames = { received: 0, decimated: 0, skippedCycles: 0 };
/** Called after every appended frame (bench/ui.py times click-to-motion with it). */
export const frameListeners = new Set<(r: Rings) => void>();

const wants = new Map<string, string[]>();
let ws: WebSocket | null = null;
let cycleS = 0.001;
let subscribedNames = ""; // the subscription sent on this socket ("" none yet) ...
let subscribedFrameS = 0; // ... and its frame period
let frameS = 0.02; // how often frames are asked for: as often as the plots redraw

/** Frames at most every `s` seconds (the plots' redraw period): at 10 draws a second, five
 * frames a draw would only wake the page, and the service, for nothing. */
export function setFramePeriod(s: number): void {
  frameS = s;
  resubscribe();
}

/** Ask for signals on behalf of `owner` (a plot); the socket streams the union. */
export function want(owner: string, names: string[]): void {
  wants.set(owner, names);
  resubscribe();
}

export function unwant(owner: string): void {
  wants.delete(owner);
  resubscribe();
}

function union(): string[] {
  const known = new Set(catalogue.value.map((s) => s.name));
  const all = new Set<string>();
  wants.forEach((names) => names.forEach((n) => known.has(n) && all.add(n)));
  return [...all].sort();
}

function resubscribe(): void {
  const names = union();
  const joined = names.join(",");
  if (!ws || ws.readyState !== WebSocket.OPEN || !names.length) return;
  if (joined === subscribedNames && frameS === subscribedFrameS) return;
  const same = joined === subscribedNames;
  subscribedNames = joined;
  subscribedFrameS = frameS;
  ws.send(JSON.stringify({ type: "subscribe", signals: names, frame_s: frameS }));
  if (same) return; // a new frame period only: the rings go on
  // the signals that stay keep their history (a plot's, while another panel adds its own)
  rings.value = Rings.carry(rings.value, names, Math.round(RING_SECONDS / cycleS));
}

export function decodeFrame(buf: ArrayBuffer): { header: FrameHeader; data: Float64Array } | null {
  const view = new DataView(buf);
  if (buf.byteLength < 8 || view.getUint32(0, true) !== MAGIC) return null;
  const n = view.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 8, n))) as FrameHeader;
  return { header, data: new Float64Array(buf, 8 + n, header.count * header.signals.length) };
}

function onFrame(buf: ArrayBuffer): void {
  const f = decodeFrame(buf);
  if (!f) return;
  const { header: h, data } = f;
  const r = rings.value;
  if (h.signals.join(",") !== r.names.join(",")) return; // a frame of the old subscription
  const times = new Float64Array(h.count);
  for (let k = 0; k < h.count; k++) times[k] = (h.first_cycle + k * h.stride) * h.cycle_s;
  if (r.size && h.count && times[0] < r.lastTime) {
    // simulated time went back (the machine was restarted or rebuilt): plot the new run only
    rings.value = new Rings(r.names, Math.round(RING_SECONDS / cycleS));
  }
  rings.value.append(times, data, h.count);
  frames.received++;
  if (h.decimated) frames.decimated++;
  frames.skippedCycles += h.skipped_cycles;
  frameListeners.forEach((f) => f(rings.value));
}

function onMessage(text: string): void {
  const msg = JSON.parse(text) as Hello | Subscribed | EventMessage | StatusMessage | NoticeMessage | HistoryMessage | ErrorMessage;
  switch (msg.type) {
    case "hello":
      cycleS = msg.cycle_s;
      catalogue.value = msg.signals;
      socket.value = "online";
      subscribedNames = "";
      resubscribe();
      break;
    case "event":
      addEvents([msg.event]);
      break;
    case "history":
      addHistory(msg.entries);
      break;
    case "status":
      statusArrived(msg.status);
      break;
    case "notice":
      // the machine's time starts again (rebuilt, the service restarted) or goes back
      // (restored): so does the event log (the history keeps what came before); a class's
      // presentation began or ended: who may see which machine changed
      if (!noticeArrived(msg)) break;
      if (msg.kind === "present") void presentationChanged().catch(() => undefined);
      else if (msg.kind === "exercise") {
        dropTrialOf(machineId.value);
        restartLog();
      } else if (msg.kind !== "message" && msg.kind !== "frozen" && msg.kind !== "resumed") restartLog();
      break;
    case "error":
      console.warn("telemetry:", msg.message);
      break;
  }
}

let attempt = 0; // a newer connect (or machine) makes an older one's pending ticket moot

async function connect(mid: string): Promise<void> {
  const mine = ++attempt;
  let ticket: WsTicket;
  try {
    ticket = await http.post<WsTicket>("/api/auth/ws-ticket", {});
  } catch {
    // a 401 ended the session already (the login screen shows); otherwise try again
    if (mine === attempt) setTimeout(() => ws === null && machineId.value === mid && void connect(mid), RECONNECT_MS);
    return;
  }
  if (mine !== attempt || machineId.value !== mid) return;
  const proto = location.protocol === "https:" ? "wss" : "ws";
  // the tab's id: the socket keeps this tab's control of the machine alive
  const query = new URLSearchParams({ ticket: ticket.ticket, client: clientId });
  const sock = new WebSocket(`${proto}://${location.host}/api/machines/${encodeURIComponent(mid)}/telemetry?${query}`);
  sock.binaryType = "arraybuffer";
  ws = sock;
  sock.onmessage = (ev) => (typeof ev.data === "string" ? onMessage(ev.data) : onFrame(ev.data as ArrayBuffer));
  let opened = false;
  sock.onopen = () => void (opened = true);
  sock.onclose = (ev) => {
    if (ws !== sock) return; // replaced on purpose
    ws = null;
    socket.value = "lost";
    // a refused handshake looks like any failed connect: a 401 from `me` says the session ended
    if (!opened || ev.code === SESSION_ENDED) void loadMe();
    if (!opened) void checkMachineStill(mid); // refused: is it still there?
    setTimeout(() => ws === null && machineId.value === mid && void connect(mid), RECONNECT_MS);
  };
}

effect(() => {
  const mid = machineId.value;
  const old = ws;
  ws = null;
  old?.close();
  subscribedNames = "";
  rings.value = new Rings([], 1); // another machine's history is not this one's
  attempt++; // a ticket still on its way is for the machine before
  if (mid) void connect(mid);
});
