"""Soak: the real service under steady load for a while (10 minutes by default), watched for
growth. Telemetry viewers (a separate client process) stream the demo lathe; a client sends
about 10 commands a second (MDI blocks, overrides, and every 10 s one the NC refuses with a
job error) and reads the machine's status and history as a page would.

Prints the resident memory (RSS) of the gateway and of every worker at the start (after a
warm-up minute) and at the end, the gateway's RSS each minute, and the store's growth (the
SQLite file and its write-ahead log) per hour; then the commands sent, refused and failed;
then the flight recorder (its memory at the start and the end, the job errors of the history
with a trace linked, those traces in the library) and the history's rows and bytes per row.
Bar: no steady growth of the gateway beyond a few MB per hour, the recorder's memory flat,
every job error with its trace, no failed request.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.service import Viewers, fresh_status
from tests.backend.server import Server

SIGNALS = ["S1.speed_act_rpm", "S1.lag_deg", "Z.pos_act_mm", "X.lag_mm"]
COMMANDS: list[dict[str, Any]] = [
    {"type": "mdi", "block": "M3 S800"},
    {"type": "override", "percent": 80.0},
    {"type": "mdi", "block": "M5"},
    {"type": "override", "percent": 100.0},
]
REFUSED: dict[str, Any] = {
    "type": "mdi",
    "block": "M3 S20000",
}  # beyond every gear range: job error 90017
RATE_HZ = 10.0
ERROR_EVERY = 100  # commands: a job error every 10 s


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def store_mb(db: Path) -> float:
    return sum(p.stat().st_size for p in db.parent.glob(db.name + "*")) / 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--warmup-s", type=float, default=60.0)
    parser.add_argument("--viewers", type=int, default=10)
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    extra = ["--workers", str(args.workers)] if args.workers else []
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "soak.sqlite"
        # every trace of the soak's errors kept, to count them
        srv = Server(db, *extra, env={"INBETRIEB_FLIGHT_KEEP": "1000"}).start()
        assert srv.proc is not None
        gateway = srv.proc.pid
        try:
            srv.wait_powered("demo")
            url = f"{srv.ws_base}/api/machines/demo/telemetry"
            viewers = Viewers([url] * args.viewers, SIGNALS, headers=srv.auth).start()
            sent = refused = failed = job_errors = 0
            commands = itertools.cycle(COMMANDS)
            t0 = time.monotonic()
            end = t0 + args.warmup_s + args.minutes * 60
            start: tuple[float, dict[str, float], float, float] | None = None
            minute = t0 + args.warmup_s
            k = 0
            while (now := time.monotonic()) < end:
                if start is None and now >= t0 + args.warmup_s:
                    workers = {w["id"]: w["pid"] for w in fresh_status(srv.http)["workers"]}
                    start = (
                        rss_mb(gateway),
                        {w: rss_mb(p) for w, p in workers.items()},
                        store_mb(db),
                        now,
                    )
                    flight0 = srv.http.get("/api/machines/demo/flight-recorder").json()["bytes"]
                    rows0 = history_rows(srv)
                    print(
                        f"after {args.warmup_s:.0f} s warm-up: gateway {start[0]:.1f} MB, "
                        + ", ".join(f"{w} {m:.1f} MB" for w, m in start[1].items())
                        + f", store {start[2]:.2f} MB",
                        flush=True,
                    )
                if start is not None and now >= minute:
                    print(
                        f"  minute {round((now - start[3]) / 60):2d}: gateway "
                        f"{rss_mb(gateway):.1f} MB, store {store_mb(db):.2f} MB",
                        flush=True,
                    )
                    minute += 60
                body = REFUSED if k % ERROR_EVERY == ERROR_EVERY - 1 else next(commands)
                r = srv.command("demo", body)
                sent += 1
                job_errors += body is REFUSED
                refused += r.status_code == 409
                failed += r.status_code not in (200, 409)
                if k % 10 == 0:  # what an open page reads now and then
                    failed += srv.http.get("/api/machines/demo/status").status_code != 200
                    page = srv.http.get("/api/machines/demo/history", params={"limit": 50})
                    failed += page.status_code != 200
                k += 1
                time.sleep(max(0.0, t0 + k / RATE_HZ - time.monotonic()))
            received = viewers.stop()
            assert start is not None
            hours = (time.monotonic() - start[3]) / 3600
            workers = {w["id"]: w["pid"] for w in fresh_status(srv.http)["workers"]}
            g1 = rss_mb(gateway)
            print(
                f"soak of {hours * 60:.1f} min, {args.viewers} viewers, "
                f"{sent / (hours * 3600 + args.warmup_s):.1f} commands/s"
            )
            print(
                f"  gateway RSS {start[0]:.1f} -> {g1:.1f} MB ({(g1 - start[0]) / hours:+.1f} MB/h)"
            )
            for wid, pid in workers.items():
                before = start[1].get(wid)
                was = f"{before:.1f}" if before is not None else "(new)"
                print(f"  worker {wid} RSS {was} -> {rss_mb(pid):.1f} MB")
            s1 = store_mb(db)
            print(
                f"  store {start[2]:.2f} -> {s1:.2f} MB ({(s1 - start[2]) / hours:+.1f} MB/h, "
                f"{(s1 - start[2]) / hours * 24:.0f} MB/day)"
            )
            frames = sum(v.frames for v in received)
            viewer_errors = [v.error for v in received if v.error]
            print(
                f"  commands {sent}, {job_errors} of them bringing a job error ({refused} "
                f"refused at once with 409, the others while queued, as an event), failed "
                f"{failed}; viewers: {frames} frames, {len(viewer_errors)} failed"
            )
            time.sleep(3.0)  # the last error's window (2 s after it) saved
            flight1 = srv.http.get("/api/machines/demo/flight-recorder").json()["bytes"]
            errors = srv.http.get(
                "/api/machines/demo/history", params={"kind": "job_error", "limit": 1000}
            ).json()["rows"]
            traced = [e for e in errors if e["trace"]]
            library = {t["id"] for t in srv.http.get("/api/traces").json()}
            print(
                f"  flight recorder: {flight0 / 1e6:.2f} -> {flight1 / 1e6:.2f} MB; "
                f"{len(errors)} job errors, {len(traced)} with a trace, "
                f"{sum(e['trace'] in library for e in traced)} of those in the library"
            )
            rows1 = history_rows(srv)
            grown = (store_mb(db) - start[2]) * 1e6
            print(
                f"  history: {rows0} -> {rows1} entries (+{(rows1 - rows0) / hours:.0f}/h), "
                f"store growth {grown / max(1, rows1 - rows0):.0f} B per entry (traces' files "
                "apart)"
            )
        finally:
            srv.close()


def history_rows(srv: Server) -> int:
    """The demo lathe's history entries (machine log and audit rows)."""
    total: int = srv.http.get("/api/machines/demo/history", params={"limit": 1}).json()["total"]
    return total


if __name__ == "__main__":
    main()
