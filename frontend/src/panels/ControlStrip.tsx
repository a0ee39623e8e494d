// Who holds the machine on screen, under the top bar: free, this tab, this session in another
// tab, or someone else; the way to ask for it, take it, hand it over or give it back; a
// holder without a live connection (a closed tab, a script) counting down to the release; what
// happened to this tab's control or request meanwhile (refused, taken, lapsed). A request
// carries a word to the holder; observers may ask too (to be heard: they cannot be granted
// control). A student of a frozen class seat is offered nothing: the strip says why.
import { watching } from "../state/presenting";
import { useState } from "preact/hooks";
import { ApiError } from "../api/http";
import type { ControlParty, Refusal } from "../api/types";
import { me } from "../state/auth";
import { act, control, controlNote, dismissControlNote, may, requested, standing, who } from "../state/control";
import { frozen, online } from "../state/session";
import { RefusalLine } from "../ui/useCommand";

export function ControlStrip() {
  const c = control.value;
  const [refusal, setRefusal] = useState<Refusal | null>(null);
  const [asking, setAsking] = useState<string | null>(null); // the request's message, as typed
  if (!c) return null;
  const h = c.holder;
  const st = standing.value;
  const dis = !online.value;
  const run = (action: Parameters<typeof act>[0], party?: ControlParty, message?: string) =>
    act(action, party, message).then(
      () => {
        setRefusal(null);
        if (action === "request") setAsking(null);
      },
      (e: unknown) => setRefusal(e instanceof ApiError ? e.refusal : { message: String(e), problems: [] }),
    );
  const button = (id: string, label: string, action: Parameters<typeof act>[0], party?: ControlParty, title = "") => (
    <button type="button" class="secondary" data-testid={id} disabled={dis} title={title} onClick={() => void run(action, party)}>
      {label}
    </button>
  );
  // a class seat frozen by the instructor: its student waits (the service refuses them, 409)
  const waiting = frozen.value !== null && !may("take_control");
  const lapseS = c.release_at_unix != null ? Math.max(0, Math.ceil(c.release_at_unix - Date.now() / 1000)) : null;
  return (
    <div class={`control-strip ${st}${waiting ? " frozen" : ""}`} data-testid="control-strip" role="status" aria-label="control of the machine">
      <span class="control-holder" data-testid="control-holder">
        {!h
          ? "Free"
          : st === "mine"
            ? waiting
              ? "You have control, frozen by the instructor"
              : "You have control"
            : st === "other-tab"
              ? "You have control in another tab"
              : `${who(h)} has control`}
      </span>
      {!may("command") ? (
        <>
          <span class="hint" data-testid="control-view-only">
            view only ({me.value?.guest ? "share link" : watching.value ? "watching the instructor's machine" : me.value?.role})
          </span>
          {!h && may("ask") ? (
            <span class="hint" data-testid="control-nobody">
              nobody has control to ask for: a note in the History reaches whoever comes
            </span>
          ) : null}
        </>
      ) : waiting ? (
        <span class="hint" data-testid="control-frozen">
          {st === "mine" ? "your commands wait until the instructor resumes the machine" : "frozen by the instructor: you can take control once they resume the machine"}
        </span>
      ) : !h ? (
        <span class="hint">the first command takes control</span>
      ) : null}
      {(c.viewers ?? []).length ? (
        <span class="viewers" data-testid="control-viewers"
          title={(c.viewers ?? []).map((v) => (v.guest ? `${v.user} (share link)` : who(v))).join(", ")}>
          ⊙ {(c.viewers ?? []).length} watching
          {(c.viewers ?? []).some((v) => v.guest) ? ` · ${(c.viewers ?? []).filter((v) => v.guest).length} by share link` : ""}
        </span>
      ) : null}
      {h && lapseS !== null ? (
        <span class="control-lost" data-testid="control-lost">
          no live connection: released in {lapseS} s
        </span>
      ) : null}
      {may("control") && !waiting ? (
        <span class="control-actions">
          {!h ? button("control-take", "Take control", "take") : null}
          {st === "mine" ? button("control-release", "Release", "release") : null}
          {st === "other-tab" ? button("control-take-here", "Take over here", "take") : null}
          {st === "other" && may("take_control")
            ? button("control-take", "Take control", "take", undefined, `take it from ${who(h!)} without asking`)
            : null}
        </span>
      ) : null}
      {st === "other" && !waiting && may("ask") && !may("take_control") && !requested.value ? (
        asking === null ? (
          <button type="button" class="secondary" data-testid="control-request" disabled={dis}
            title={may("control") ? `ask ${who(h!)} to hand it over` : `ask ${who(h!)} for their attention (you may watch only)`}
            onClick={() => setAsking("")}>
            {may("control") ? "Request control…" : "Ask for control…"}
          </button>
        ) : (
          <form class="control-ask" onSubmit={(e) => { e.preventDefault(); void run("request", undefined, asking); }}>
            <input data-testid="control-request-message" maxLength={300} size={48} value={asking} aria-label={`a word to ${who(h!)}`}
              placeholder="why, for how long (optional)" onInput={(e) => setAsking((e.target as HTMLInputElement).value)} />
            <button type="submit" data-testid="control-request-send" disabled={dis}>
              Send request
            </button>
            <button type="button" class="secondary" onClick={() => setAsking(null)}>
              Cancel
            </button>
          </form>
        )
      ) : null}
      {st === "other" && requested.value ? (
        <span class="control-actions">
          <span class="hint" data-testid="control-requested">
            requested…
          </span>
          {button("control-cancel", "Cancel request", "cancel")}
        </span>
      ) : null}
      {st === "mine"
        ? (c.requests ?? []).map((r) => (
            <span class="control-request" data-testid="control-incoming" key={`${r.session}/${r.client}`}>
              <b>{who(r)}</b> asks for control{r.message ? <q data-testid="control-request-said">{r.message}</q> : null}
              {r.role === "observer" ? null : button("control-grant", "Grant", "grant", r)}
              {button("control-refuse", r.role === "observer" ? "Seen" : "Refuse", "refuse", r,
                r.role === "observer" ? "an observer may watch only: this tells them you saw it and closes the request" : "")}
            </span>
          ))
        : null}
      {controlNote.value ? (
        <span class="control-note" data-testid="control-note">
          {controlNote.value}
          <button type="button" class="secondary" data-testid="control-note-dismiss" title="dismiss" onClick={dismissControlNote}>
            ×
          </button>
        </span>
      ) : null}
      <RefusalLine refusal={refusal} id="control-refusal" />
    </div>
  );
}
