"""`inbetrieb backup` while the service serves (20 viewers watching, a script writing a
parameter as fast as it is acknowledged) and `inbetrieb restore` into a fresh place: every
write acknowledged before the backup began is in the restored store, in order, the store's
integrity check says ok, and a trace saved before is there with its data."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import threading
from pathlib import Path

from websockets.asyncio.client import connect

from tests.backend.server import ROOT, Server

VIEWERS = 20
NAME = "getriebe[0].kv"  # X's kv (0.01/s): a value that changes at once, audited each time


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "backend.cli", *args], cwd=ROOT, capture_output=True, text=True
    )


def test_a_backup_while_serving_restores_every_acknowledged_write(tmp_path: Path) -> None:
    s = Server(tmp_path / "live" / "store.sqlite").start()
    acked: list[int] = []  # the values the service acknowledged, in order
    stop = threading.Event()
    watching = threading.Event()

    def write() -> None:
        value = 2000
        while not stop.is_set():
            value += 1
            body = {"changes": [{"scope": "axis", "target": "X", "name": NAME, "value": value}]}
            if s.http.patch("/api/machines/demo/parameters", json=body).status_code == 200:
                acked.append(value)

    async def viewers() -> None:
        url = f"{s.ws_base}/api/machines/demo/telemetry?signals=X.lag_mm"
        socks = [await connect(url, **s.ws_auth) for _ in range(VIEWERS)]
        watching.set()
        while not stop.is_set():
            await asyncio.gather(*(ws.recv() for ws in socks))
        for ws in socks:
            await ws.close()

    seen = threading.Thread(target=lambda: asyncio.run(viewers()), daemon=True)
    writer = threading.Thread(target=write, daemon=True)
    try:
        tid = s.http.post(
            "/api/traces/import",
            content=b"t_s,X.lag_mm [mm]\n0.0,1.0\n0.001,2.5\n",
            headers={"content-type": "text/csv"},
        ).json()["id"]
        seen.start()
        assert watching.wait(30)
        writer.start()
        while len(acked) < 20:  # writes under way
            stop.wait(0.05)
        before = acked[-1]  # acknowledged before the backup began
        archive = tmp_path / "inbetrieb.tar.gz"
        done = _cli("backup", str(archive), "--db", str(s.db))
        assert done.returncode == 0, done.stderr
        during = len(acked)
        while len(acked) < during + 10:  # the writes went on during and after it
            stop.wait(0.05)
    finally:
        stop.set()
        for t in (writer, seen):  # before the service goes: no request is cut off
            if t.is_alive():
                t.join(30)
        s.close()
    assert "backed up to" in done.stdout and "trace files" in done.stdout

    restored = tmp_path / "restored" / "store.sqlite"
    done = _cli("restore", str(archive), "--db", str(restored))
    assert done.returncode == 0, done.stderr
    r = Server(restored).start()
    try:
        rows = r.http.get(
            "/api/machines/demo/parameters", params={"scope": "axis", "target": "X"}
        ).json()
        kept = next(p["value"] for p in rows if p["name"] == NAME)
        assert before <= kept <= acked[-1]  # every write acknowledged before is in it
        history = r.http.get(
            "/api/machines/demo/history", params={"kind": "parameter", "limit": 1000}
        ).json()["rows"]
        values = sorted(
            int(h["text"].rsplit(" ", 1)[-1])
            for h in history
            if NAME in h["text"] and "→" in h["text"]
        )
        assert [v for v in acked if v <= kept] == [v for v in values if v <= kept]
        data = r.http.get(f"/api/traces/{tid}/data")
        assert data.status_code == 200, data.text
        # while it is served, the store is nobody else's: no restore over it, no second service
        busy = _cli("restore", str(archive), "--db", str(restored))
        assert busy.returncode == 2 and "stop it first" in busy.stderr, busy.stderr
        assert not any(".before-restore-" in p.name for p in restored.parent.iterdir())
        twice = _cli("serve", "--port", "1", "--db", str(restored))
        assert twice.returncode == 2 and "served by another process" in twice.stderr
    finally:
        r.close()
    # the restore kept what was in the way; a second one onto the same place works again
    done = _cli("restore", str(archive), "--db", str(restored))
    assert done.returncode == 0, done.stderr
    assert any(p.name.startswith("store.sqlite.before-restore-") for p in restored.parent.iterdir())


def test_a_restore_refuses_what_is_no_backup(tmp_path: Path) -> None:
    bad = tmp_path / "x.tar.gz"
    bad.write_bytes(b"not a tar")
    done = _cli("restore", str(bad), "--db", str(tmp_path / "s.sqlite"))
    assert done.returncode == 2 and "not an Inbetrieb backup" in done.stderr
    assert not (tmp_path / "s.sqlite").exists()
