// The strip a class's student sees while their instructor presents a machine: watch it (read-
// only) or go back to their own seat.
import { me } from "../state/auth";
import { ownSeat, watching } from "../state/presenting";
import { selectMachine } from "../state/session";

export function PresentStrip() {
  const w = me.value?.watches;
  if (!w) return null;
  return (
    <div class="present-strip" role="status" data-testid="present-strip">
      {watching.value ? (
        <>
          ▣ You are watching your instructor's machine <b>{w}</b> (read-only).{" "}
          <button type="button" data-testid="present-back" onClick={() => selectMachine(ownSeat.value)}>Back to my seat</button>
        </>
      ) : (
        <>
          ▣ Your instructor presents machine <b>{w}</b>.{" "}
          <button type="button" data-testid="present-watch" onClick={() => selectMachine(w)}>Watch it</button>
        </>
      )}
    </div>
  );
}
