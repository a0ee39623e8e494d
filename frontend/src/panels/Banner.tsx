// Connection loss, notices (a machine rebuilt after its worker died), an assistant running
// live on the machine (outside the Commissioning workspace, which shows it itself) and the
// newest job error still active, until acknowledged or reset.
import { acknowledgeBanner, bannerErrors } from "../state/events";
import { connection, notice } from "../state/session";
import { qty } from "../ui/format";
import { LiveProgress } from "./LiveProgress";

export function Banner({ liveRun }: { liveRun: boolean }) {
  const [err, ...more] = bannerErrors.value;
  const n = notice.value;
  return (
    <div class="banners">
      {connection.value === "lost" ? (
        <div class="banner lost" role="alert" data-testid="banner-connection">
          ⚠ Connection to the service lost: controls are locked and jog keys released. Reconnecting…
        </div>
      ) : null}
      {n ? (
        <div class="banner notice" role="alert" data-testid="banner-notice">
          <span>
            ⚠ {new Date(n.time_unix * 1000).toLocaleTimeString()}: {n.message}
          </span>
          <button onClick={() => (notice.value = null)}>Dismiss</button>
        </div>
      ) : null}
      {liveRun ? <LiveProgress compact /> : null}
      {err ? (
        <div class="banner error" role="alert" data-testid="banner-error">
          <span>
            ✖ Job error <b>{err.code}</b> {err.axis ? `[${err.axis}]` : ""} at t = {qty(err.t_s, 3, "s")}: {err.message}
            {more.length ? ` (+${more.length} more active)` : ""}
          </span>
          <button onClick={acknowledgeBanner}>Acknowledge</button>
        </div>
      ) : null}
    </div>
  );
}
