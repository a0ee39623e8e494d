// The jog panel's settings (kept per machine across workspaces) and press-and-hold jog with a
// dead-man: while a key is held the start command is renewed every
// RENEW_MS with a lease of HOLD_S (simulated seconds); the service stops the jog when renewals
// stop. Releasing, leaving the window, hiding the tab and losing the connection all release.
import { effect, signal } from "@preact/signals";
import { online, send } from "./session";
import { kept } from "./workspace";

/** The jog panel's choices: the axis, the jog feed as typed (null: the G200 default) and the
 * increment of a step. */
export const jogSettings = kept<{ axis: string; feed: string | null; step: number }>("jog", {
  axis: "X",
  feed: null,
  step: 1,
});

export const HOLD_S = 0.5;
const RENEW_MS = 150;

interface Held {
  axis: string;
  timer: number;
}
let held: Held | null = null;
/** The key held now, e.g. "X+" (null: none); the jog keys show it. */
export const heldKey = signal<string | null>(null);

export const keyName = (axis: string, direction: 1 | -1) => `${axis}${direction > 0 ? "+" : "−"}`;

/** Start holding a jog key; any earlier hold is released first. */
export function holdJog(axis: string, direction: 1 | -1, feed: number | null, onRefused: (e: unknown) => void): void {
  releaseJog();
  const cmd = {
    type: "jog" as const,
    axis,
    action: "start" as const,
    direction,
    feed_mm_min: feed,
    hold_s: HOLD_S,
  };
  const renew = () =>
    send(cmd).catch((e) => {
      releaseJog();
      onRefused(e);
    });
  held = { axis, timer: window.setInterval(renew, RENEW_MS) };
  void renew();
  heldKey.value = keyName(axis, direction);
}

/** Release the held key (only if it is `key`, when given): stop renewing and tell the service
 * to brake now. */
export function releaseJog(key?: string): void {
  if (!held || (key !== undefined && heldKey.value !== key)) return;
  const { axis, timer } = held;
  clearInterval(timer);
  held = null;
  heldKey.value = null;
  send({ type: "jog", axis, action: "stop", direction: 1 }).catch(() => undefined); // the lease ends it anyway
}

window.addEventListener("blur", () => releaseJog());
window.addEventListener("pagehide", () => releaseJog());
document.addEventListener("visibilitychange", () => document.hidden && releaseJog());
effect(() => {
  if (!online.value) releaseJog();
});
