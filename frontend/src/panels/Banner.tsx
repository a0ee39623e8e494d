// Connection loss, a class seat frozen by the instructor (while it is), notices (a machine
// rebuilt after its worker died or restored, the instructor's messages), an assistant running
// live on the machine (outside the Commissioning workspace, which shows it itself) and the
// first job error still active (the cause; later ones counted), until dismissed (hidden
// only) or cleared by a reset.
import type { NoticeMessage } from "../api/types";
import { dismissBanner, bannerErrors } from "../state/events";
import { http } from "../api/http";
import { may } from "../state/control";
import { connection, dismissNotice, frozen, machineId, notices } from "../state/session";
import { qty } from "../ui/format";
import { LiveProgress } from "./LiveProgress";

export function Banner({ liveRun }: { liveRun: boolean }) {
  const [err, ...more] = bannerErrors.value;
  return (
    <div class="banners">
      {connection.value === "lost" ? (
        <div class="banner lost" role="alert" data-testid="banner-connection">
          ⚠ Connection to the service lost: controls are locked and jog keys released. Reconnecting…
        </div>
      ) : null}
      {frozen.value !== null ? (
        <div class="banner frozen" role="alert" data-testid="banner-frozen">
          <span>
            ❚❚ Frozen by the instructor — the machine is paused. Only the instructor can resume it.
            {frozen.value ? <span class="banner-detail"> ({frozen.value})</span> : null}
          </span>
        </div>
      ) : null}
      {notices.value.map((n) => (
        <div key={n.seq} class={`banner notice ${n.kind}`} role="alert" data-testid="banner-notice" data-kind={n.kind}>
          <span>{noticeText(n)}</span>
          <button onClick={() => dismissNotice(n.seq)}>Dismiss</button>
        </div>
      ))}
      {liveRun ? <LiveProgress compact /> : null}
      {err ? (
        <div class="banner error" role="alert" data-testid="banner-error">
          <span>
            ✖ Job error <b>{err.code}</b> {err.axis ? `[${err.axis}]` : ""} at t = {qty(err.t_s, 3, "s")}: {err.message}
            {more.length ? ` (+${more.length} later, still active)` : ""}
          </span>
          <span class="banner-detail"> Reset clears it.</span>
          <button onClick={acknowledge}
            title={may("note") ? "Hide this banner; the machine's history records that you saw it. The error stays active until Reset" : "Hide this banner on this page. The error stays active until Reset"}>
            Dismiss
          </button>
        </div>
      ) : null}
    </div>
  );
}

/** Hide the banner's errors and, for whoever may write in the logbook, put down in the
 * history who saw them (nothing is lost if that fails: the banner hides all the same). */
function acknowledge(): void {
  dismissBanner();
  if (may("note")) void http.post(`/api/machines/${encodeURIComponent(machineId.value)}/history/acknowledge`, {}).catch(() => undefined);
}

function noticeText(n: NoticeMessage): string {
  const at = new Date(n.time_unix * 1000).toLocaleTimeString();
  switch (n.kind) {
    case "message":
      return `✉ ${at}: Message from ${n.message}`; // the service writes "<name>: <text>"
    case "resumed":
      return `▶ ${at}: ${n.message}`;
    case "present":
      return `▣ ${at}: ${n.message}`;
    case "exercise":
      return `▸ ${at}: ${n.message}`;
    default:
      return `⚠ ${at}: ${n.message}`;
  }
}
