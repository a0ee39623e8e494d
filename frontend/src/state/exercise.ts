// The exercise of the chosen machine when it is a class seat (the machine list says which
// are): asked for when the machine changes, refreshed while the Exercise tab shows it;
// hints are taken from here. The service hides the exercise's faults from the student.
import { computed, effect, signal, untracked } from "@preact/signals";
import { ApiError, http } from "../api/http";
import type { AnswerGiven, Exercise, HintInfo, RaisedHand } from "../api/types";
import { freezeNoticeCount, machineId, machines, machineUrl, seatFrozen } from "./session";

const SEAT_KEY = "inbetrieb.seat"; // this browser was a class seat's student's (the class id)

/** Whether this browser was last logged in as a class seat's student (their login page
 * tells them to ask their instructor for a link, not about the service's start). */
export const wasSeat = (): boolean => localStorage.getItem(SEAT_KEY) !== null;
/** Someone logged in with a password (no seat's student has one): the browser is no seat's. */
export const forgetSeat = (): void => localStorage.removeItem(SEAT_KEY);

/** The seat's exercise as it stands; null while the machine is no class seat (or unknown). */
export const exercise = signal<Exercise | null>(null);

/** This browser's student as their seat's exercise names them (kept while they watch a
 * machine their instructor presents): their name in the top bar. */
export const seatStudent = signal<{ user: string; student: string; seat: number } | null>(null);

/** The assistants the seat's exercise locks for this browser's user (its student; an
 * instructor watching may use them). */
export const lockedAssistants = computed<readonly string[]>(() => {
  const ex = exercise.value;
  return ex?.takes_hints ? ex.exercise.locked_assistants : [];
});

/** Move the seat on to its lesson plan's next exercise (its student once every check has
 * passed; an instructor at any time): the machine powers on afresh for it. */
export async function moveOn(): Promise<void> {
  exercise.value = await http.post<Exercise>(machineUrl("/exercise/next"), {});
}

/** Ask the service for the seat's exercise again (checks, score, hints, frozen). */
export async function refreshExercise(): Promise<void> {
  const mid = machineId.value;
  if (!mid) return;
  if (!machines.peek().find((m) => m.id === mid)?.seat) return void (exercise.value = null); // no seat: nothing to ask
  const asked = freezeNoticeCount();
  try {
    const ex = await http.get<Exercise>(machineUrl("/exercise"));
    if (machineId.value !== mid) return; // an answer about the machine before
    exercise.value = ex;
    if (ex.takes_hints) {
      localStorage.setItem(SEAT_KEY, ex.class_id); // the login page's help
      seatStudent.value = { user: ex.user, student: ex.student, seat: ex.seat };
    }
    seatFrozen(ex.frozen, asked);
  } catch (e) {
    // no seat (404), or a role that reads no exercise: no tab; a lost connection keeps it
    if (machineId.value === mid && e instanceof ApiError && e.status !== 0) exercise.value = null;
  }
}

/** Raise the seat's hand (with a word for the instructor) or lower it. */
export async function raiseHand(raised: boolean, text = ""): Promise<void> {
  await http.post<RaisedHand | null>(machineUrl("/exercise/hand"), { raised, text });
  await refreshExercise();
}

/** Take hint n: its text (its cost comes off the score once). */
export async function takeHint(n: number): Promise<HintInfo> {
  const hint = await http.post<HintInfo>(machineUrl("/exercise/hints"), { n });
  await refreshExercise();
  return hint;
}

/** Answer finding `check`: `axis` carries the fault, `value` its size in the axis' unit
 * (mm | °). Graded at once; each answer uses one of the check's attempts. */
export async function answerFinding(check: string, axis: string, value: number): Promise<AnswerGiven> {
  const given = await http.post<AnswerGiven>(machineUrl("/exercise/findings"), { check, axis, value });
  await refreshExercise();
  return given;
}

effect(() => {
  void machineId.value; // another machine: another seat, or none
  untracked(() => {
    exercise.value = null;
    void refreshExercise();
  });
});
