// Handshakes with the PLC the NC waits for (an M function to acknowledge, a mode request to
// answer), in the operator's words, with the time left before the NC gives up (job error 90004
// at the pending's timeout cycle, P-CHAN plc.m_ack_timeout after the output).
import { computed } from "@preact/signals";
import type { PendingM } from "../api/types";
import { status } from "./session";

const GEARS = { first: 40, last: 45 }; // M40..M45: gear stages 1..6 [000 §2.8]

/** What the NC waits for, e.g. "gear change M42 (S1): PLC acknowledge". */
export function waitedFor(p: PendingM): string {
  const on = p.axis ? ` (${p.axis})` : "";
  if (p.signal === "ROTMOD") return `changeover to the rotary axis${on}: ROTMOD_Q from the PLC`;
  if (p.signal === "SPMOD") return `changeover to spindle mode${on}: SPMOD_Q from the PLC`;
  if (p.signal) return `${p.signal}${on}: ${p.signal}_Q from the PLC`;
  if (p.m !== null && p.m >= GEARS.first && p.m <= GEARS.last) return `gear change M${p.m}${on}: PLC acknowledge`;
  return `M${p.m}${on}: PLC acknowledge`;
}

/** Simulated seconds left before the NC gives up on `p` (null: it does not say). */
export function secondsLeft(p: PendingM): number | null {
  const sim = status.value?.simulation;
  if (!sim || p.timeout_cycle == null) return null;
  return Math.max(0, (p.timeout_cycle - sim.cycle) * sim.cycle_s);
}

/** The key and command that answer `p` as the PLC would. */
export function answerOf(p: PendingM) {
  return p.signal
    ? { label: `Set ${p.signal}_Q`, cmd: { type: "plc_signal" as const, signal: p.signal === "SPMOD" ? ("SPMOD_Q" as const) : ("ROTMOD_Q" as const), on: true } }
    : { label: "Acknowledge", cmd: { type: "plc_ack" as const, m: p.m } };
}

/** Pending handshakes worth the operator's attention: every one while the PLC does not answer
 * by itself (manual, fault); in auto mode those waiting longer than its delay (a PLC that
 * should have answered). */
export const pendingHandshakes = computed<PendingM[]>(() => {
  const s = status.value;
  if (!s) return [];
  const { mode, ack_delay_s, pending } = s.plc;
  if (mode !== "auto") return pending;
  const now = s.simulation.cycle;
  return pending.filter((p) => (now - p.out_cycle) * s.simulation.cycle_s > ack_delay_s + 0.2);
});
