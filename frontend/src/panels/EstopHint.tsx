// Beside Reset while an emergency stop is active: who stopped the machine (the newest
// emergency stop in the machine's audit, which everyone who watches may read) and who ends it.
import { useEffect, useState } from "preact/hooks";
import { http } from "../api/http";
import type { AuditPage } from "../api/types";
import { machineUrl, status } from "../state/session";

export function EstopHint() {
  const active = !!status.value?.emergency_stop;
  const [by, setBy] = useState("");
  useEffect(() => {
    setBy("");
    if (!active) return;
    let current = true;
    http
      .get<AuditPage>(machineUrl("/audit?kind=command&text=emergency&limit=1"))
      .then((page) => current && setBy(page.rows[0]?.outcome === "ok" ? page.rows[0].actor : ""))
      .catch(() => undefined); // the hint then names nobody
    return () => void (current = false);
  }, [active]);
  if (!active) return null;
  return (
    <span class="hint estop-hint" data-testid="estop-hint">
      Emergency stop{by ? ` by ${by}` : ""}: the control holder resets (Reset)
    </span>
  );
}
