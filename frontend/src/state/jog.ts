// Press-and-hold jog with a dead-man: while a key is held the start command is renewed every
// RENEW_MS with a lease of HOLD_S (simulated seconds); the service stops the jog when renewals
// stop. Releasing, leaving the window, hiding the tab and losing the connection all release.
import { effect } from "@preact/signals";
import { online, send } from "./session";

export const HOLD_S = 0.5;
const RENEW_MS = 150;

interface Held {
  axis: string;
  timer: number;
}
let held: Held | null = null;
export const jogListeners = new Set<(axis: string | null) => void>();

function notify(): void {
  jogListeners.forEach((f) => f(held?.axis ?? null));
}

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
  notify();
}

/** Release the held key: stop renewing and tell the service to brake now. */
export function releaseJog(): void {
  if (!held) return;
  const { axis, timer } = held;
  clearInterval(timer);
  held = null;
  notify();
  send({ type: "jog", axis, action: "stop", direction: 1 }).catch(() => undefined); // the lease ends it anyway
}

window.addEventListener("blur", releaseJog);
window.addEventListener("pagehide", releaseJog);
document.addEventListener("visibilitychange", () => document.hidden && releaseJog());
effect(() => {
  if (!online.value) releaseJog();
});
