// Control of the machine on screen: one tab of one session holds it (api/control.py). The state
// comes with every pushed status; this tab asks for it, grants or refuses, releases. What a
// user may do at all is their role's actions (`me.actions`); what they may do now also
// depends on who holds the machine.
import { computed, effect, signal } from "@preact/signals";
import { clientId, http } from "../api/http";
import type { Action, ControlAction, ControlParty, ControlState } from "../api/types";
import { me } from "./auth";
import { exercise } from "./exercise";
import { watching } from "./presenting";
import { frozen, machineUrl, status } from "./session";

/** The user's role allows `action` (api/auth.py ALLOWED, as /api/auth/me reports it). */
export const may = (action: Action): boolean =>
  !!me.value?.actions.includes(action) && (action === "observe" || !watching.value);

export const control = computed<ControlState | null>(() => status.value?.control ?? null);

/** A party in words: "NAME (role)" as the service names one in its refusals; a class seat's
 * own login by its student's name ("Anna (seat 1)"). */
export function who(p: ControlParty): string {
  const seat = exercise.value;
  return seat && p.user === seat.user ? `${seat.student} (seat ${seat.seat})` : `${p.user} (${p.role})`;
}

const partyKey = (p: ControlParty | null | undefined) => (p ? `${p.session}/${p.client}` : "");
const isMe = (p: ControlParty) => p.session === me.value?.session && p.client === clientId;

/** How this tab stands: the machine is free, this tab holds it, this session holds it in
 * another tab, or someone else holds it. */
export type Standing = "free" | "mine" | "other-tab" | "other";
export const standing = computed<Standing>(() => {
  const h = control.value?.holder;
  if (!h) return "free";
  if (isMe(h)) return "mine";
  return h.session === me.value?.session ? "other-tab" : "other";
});

/** This tab's request waiting for the holder's answer. */
export const requested = computed(() => !!control.value?.requests?.some(isMe));

/** Why this tab cannot do a held `action` (command, configure) now; "" when it can (a free
 * machine is taken by the first command). Buttons show it as their title. */
export function blockedWhy(action: Action = "command"): string {
  const role = me.value?.role ?? "";
  if (watching.value) return "you are watching your instructor's machine: read-only";
  if (!may(action)) return `a user in the role ${role} may not ${action === "configure" ? "write parameters" : "command"}`;
  // a class seat the instructor froze: its student waits, whoever holds it
  if (frozen.value !== null && !may("take_control")) return "frozen by the instructor: the machine is paused until they resume it";
  const h = control.value?.holder;
  if (!h || standing.value === "mine") return "";
  if (standing.value === "other-tab") return "you have control in another tab: take over here to act";
  return `${who(h)} has control: request it to act`;
}

export const commandBlocked = computed(() => blockedWhy("command"));
export const configureBlocked = computed(() => blockedWhy("configure"));

/** Take, request, cancel, grant, refuse or release; rejects with the refusal (ApiError). The
 * answer is shown at once; the pushed status confirms it. */
export async function act(action: ControlAction["action"], party?: ControlParty, message?: string): Promise<void> {
  ownVerb = action; // what follows from it is no news to this tab
  const body: ControlAction = { action, session: party?.session ?? null, client: party?.client ?? null, message: message ?? null };
  const state = await http.post<ControlState>(machineUrl("/control"), body);
  const st = status.value;
  if (st && state.seq >= (st.control?.seq ?? 0)) status.value = { ...st, control: state };
}

/** Who holds the machine, as a key that changes only when the holder does. */
export const holderKey = computed(() => partyKey(control.value?.holder));

const NOTE_MS = 10_000;
/** What happened to this tab's control or request without its doing (refused, taken,
 * lapsed), read from successive pushed states; fades after NOTE_MS or is dismissed. */
export const controlNote = signal("");
let noteTimer: ReturnType<typeof setTimeout> | undefined;
function note(text: string): void {
  clearTimeout(noteTimer);
  controlNote.value = text;
  if (text) noteTimer = setTimeout(() => (controlNote.value = ""), NOTE_MS);
}
export const dismissControlNote = () => note("");

let ownVerb: ControlAction["action"] | null = null; // this tab's last control action
let before: { holder: ControlParty | null; requested: boolean; lapses: number } | null = null;

/** Why this tab lost control or its request between two states, or "" (nothing it should hear of). */
function lossNote(was: NonNullable<typeof before>, now: NonNullable<typeof before>, verb: typeof ownVerb): string {
  const h = now.holder;
  if (was.holder && isMe(was.holder) && !(h && isMe(h))) {
    if (!h) return verb === "release" ? "" : "control released: no live connection";
    if (verb === "grant") return "";
    return h.session === me.value?.session ? "you took control over in another tab" : `${who(h)} took control from you`;
  }
  if (was.requested && !now.requested && !(h && isMe(h)) && verb !== "cancel") {
    if (partyKey(was.holder) === partyKey(h) && h) {
      // gone before its time: answered; at its time: nobody answered
      if (Date.now() / 1000 >= was.lapses - 1) return `your request lapsed: ${who(h)} did not answer within a minute`;
      return may("control") ? `${who(h)} refused your request` : `${who(h)} has seen your request (you may watch only)`;
    }
  }
  return "";
}

effect(() => {
  const c = control.value;
  if (!c || !me.value) {
    before = null; // another machine, or logged out: a new story
    note("");
    return;
  }
  const mine = c.requests?.find(isMe);
  const now = { holder: c.holder ?? null, requested: !!mine, lapses: mine?.lapses_unix ?? 0 };
  const was = before;
  before = now;
  if (!was || (partyKey(was.holder) === partyKey(now.holder) && was.requested === now.requested)) return;
  const text = lossNote(was, now, ownVerb);
  ownVerb = null;
  note(text);
});
