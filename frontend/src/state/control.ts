// Control of the machine on screen: one tab of one session holds it (api/control.py). The state
// comes with every pushed status; this tab asks for it, grants or refuses, releases. What a
// user may do at all is their role's actions (`me.actions`); what they may do now also
// depends on who holds the machine.
import { computed } from "@preact/signals";
import { clientId, http } from "../api/http";
import type { Action, ControlAction, ControlParty, ControlState } from "../api/types";
import { me } from "./auth";
import { machineUrl, status } from "./session";

/** The user's role allows `action` (api/auth.py ALLOWED, as /api/auth/me reports it). */
export const may = (action: Action): boolean => !!me.value?.actions.includes(action);

export const control = computed<ControlState | null>(() => status.value?.control ?? null);

/** "NAME (role)", as the service names a party in its refusals. */
export const who = (p: ControlParty) => `${p.user} (${p.role})`;

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
  if (!may(action)) return `a user in the role ${role} may not ${action === "configure" ? "write parameters" : "command"}`;
  const h = control.value?.holder;
  if (!h || standing.value === "mine") return "";
  if (standing.value === "other-tab") return "you have control in another tab: take over here to act";
  return `${who(h)} has control: request it to act`;
}

export const commandBlocked = computed(() => blockedWhy("command"));
export const configureBlocked = computed(() => blockedWhy("configure"));

/** Take, request, cancel, grant, refuse or release; rejects with the refusal (ApiError). The
 * answer is shown at once; the pushed status confirms it. */
export async function act(action: ControlAction["action"], party?: ControlParty): Promise<void> {
  const body: ControlAction = { action, session: party?.session ?? null, client: party?.client ?? null };
  const state = await http.post<ControlState>(machineUrl("/control"), body);
  const st = status.value;
  if (st) status.value = { ...st, control: state };
}
