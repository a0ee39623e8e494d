"""Machines in worker processes, against a real service with two workers: a worker killed
with SIGKILL has its machines rebuilt from their stored parameters on a live worker while
machines on the other worker stream on without a gap, and an emergency stop takes effect
within 2 ms of reaching its worker while another client floods commands."""

from __future__ import annotations

import asyncio
import itertools
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from websockets.asyncio.client import connect

from api.telemetry import FrameHeader, decode_frame
from tests.backend.server import ROOT, Server, free_port
from tests.backend.test_parameters import lag_at_feed, write

ESTOP_WITHIN_MS = 2.0  # the bound, from the command reaching its worker
ESTOP_OUTLIER_MS = 10.0  # the one late stop allowed among 20 (see the test)


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("workers") / "w.sqlite", "--workers", "2").start()
    yield s
    s.close()


def service(srv: Server) -> dict[str, Any]:
    data: dict[str, Any] = srv.http.get("/api/service/status").json()
    return data


def worker_of(srv: Server, mid: str) -> dict[str, Any]:
    (w,) = [w for w in service(srv)["workers"] if mid in w["machines"] and w["alive"]]
    found: dict[str, Any] = w
    return found


def wait_for(pred: Any, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        if time.monotonic() > deadline:
            raise AssertionError("not reached")
        time.sleep(0.05)


def two_machines_apart(srv: Server) -> tuple[str, str]:
    """Two new machines, placed by load on different workers."""
    ids = []
    for name in ("victim", "bystander"):
        r = srv.http.post("/api/machines", json={"id": name, "demo": True})
        assert r.status_code == 201, r.text
        srv.wait_powered(name)
        ids.append(name)
    if worker_of(srv, ids[0])["id"] == worker_of(srv, ids[1])["id"]:
        ids.reverse()  # both joined the emptier worker: a third machine will not
        r = srv.http.post("/api/machines", json={"id": "third", "demo": True})
        assert r.status_code == 201
        ids = [ids[0], "third"]
        srv.wait_powered("third")
    assert worker_of(srv, ids[0])["id"] != worker_of(srv, ids[1])["id"]
    return ids[0], ids[1]


async def watch(
    srv: Server, mid: str, stop: asyncio.Event
) -> tuple[list[FrameHeader], list[dict[str, Any]]]:
    """Frames and JSON messages of one viewer until `stop`."""
    frames: list[FrameHeader] = []
    texts: list[dict[str, Any]] = []
    url = f"{srv.ws_base}/api/machines/{mid}/telemetry?signals=X.pos_act_mm"
    async with connect(url, **srv.ws_auth) as ws:
        while not stop.is_set():
            try:
                msg = await asyncio.wait_for(ws.recv(), 0.2)
            except TimeoutError:
                continue
            if isinstance(msg, bytes):
                frames.append(decode_frame(msg)[0])
            else:
                texts.append(json.loads(msg))
    return frames, texts


def test_a_killed_worker_s_machines_are_rebuilt_and_the_others_never_notice(srv: Server) -> None:
    victim, bystander = two_machines_apart(srv)
    # a stored value the rebuilt machine must run with: kv 1000 (default 2000) doubles the lag
    assert write(srv, victim, ("axis", "X", "getriebe[0].kv", 1000)).status_code == 200
    dead = worker_of(srv, victim)
    before = service(srv)

    async def scenario() -> list[tuple[list[FrameHeader], list[dict[str, Any]]]]:
        stop = asyncio.Event()
        tasks = [asyncio.create_task(watch(srv, m, stop)) for m in (victim, bystander)]
        await asyncio.sleep(1.0)
        os.kill(dead["pid"], signal.SIGKILL)
        await asyncio.to_thread(wait_for, lambda: service(srv)["machines_rebuilt"] > 0)
        await asyncio.sleep(1.0)
        stop.set()
        return list(await asyncio.gather(*tasks))

    (v_frames, v_texts), (b_frames, _) = asyncio.run(scenario())
    after = service(srv)
    assert after["machines_rebuilt"] == before["machines_rebuilt"] + 1
    home = worker_of(srv, victim)
    assert home["id"] != dead["id"] and home["pid"] != dead["pid"]
    # the victim's viewer was told, and its frames restart at cycle 1 of the new build
    notices = [t for t in v_texts if t["type"] == "notice"]
    assert [n["kind"] for n in notices] == ["rebuilt"] and dead["id"] in notices[0]["message"]
    restart = next(
        i for i, h in enumerate(v_frames) if i and h.first_cycle < v_frames[i - 1].first_cycle
    )
    assert v_frames[restart].first_cycle <= 50
    # the bystander streamed every cycle throughout: consecutive frames, nothing skipped
    assert len(b_frames) > 50
    for prev, h in itertools.pairwise(b_frames):
        assert h.first_cycle == prev.first_cycle + prev.count * prev.stride
        assert h.skipped_cycles == 0
    # rebuilt from its stored parameters: kv 1000 gives a lag of v/kv = 10 mm/s / 10 1/s
    srv.wait_powered(victim)
    assert lag_at_feed(srv, victim, 600) == pytest.approx(1.0, rel=1e-3)
    # a replacement worker took the dead one's place, and a share of its machines: the
    # survivor did not get them all
    wait_for(lambda: sum(w["alive"] for w in service(srv)["workers"]) == 2)
    assert service(srv)["workers_replaced"] == before["workers_replaced"] + 1
    old = {w["id"] for w in before["workers"]}
    (fresh,) = [w for w in service(srv)["workers"] if w["id"] not in old]
    assert fresh["machines"], "the replacement runs none of the rebuilt machines"


def test_an_emergency_stop_takes_effect_within_2_ms_under_a_flood(srv: Server, mid: str) -> None:
    """Another client sends jog start/stop and MDI blocks back to back; each emergency stop
    meanwhile acts in the kernel within 2 ms of reaching the machine's worker."""
    flooding = threading.Event()
    sent = [0]

    def flood() -> None:
        with httpx.Client(base_url=srv.base, timeout=10) as c:
            url = f"/api/machines/{mid}/commands"
            while not flooding.is_set():
                c.post(url, json={"type": "jog", "axis": "Z", "action": "start", "direction": 1})
                c.post(url, json={"type": "jog", "axis": "Z", "action": "stop"})
                c.post(url, json={"type": "mdi", "block": "M3 S100"})
                sent[0] += 3

    thread = threading.Thread(target=flood, daemon=True)
    thread.start()
    try:
        wait_for(lambda: sent[0] > 300)
        latencies = []
        for _ in range(20):
            r = srv.emergency_stop(mid)
            assert r.status_code == 200, r.text
            latencies.append(r.json()["latency_ms"])
            assert srv.command(mid, {"type": "reset"}).status_code == 200
            time.sleep(0.02)
    finally:
        flooding.set()
        thread.join(timeout=10)
    assert sent[0] > 300  # the flood ran throughout
    assert min(latencies) > 0.0  # measured, not a default
    # On this 2-core VM about one emergency stop in a hundred takes 2-6 ms (the host
    # scheduling the worker late); the bound holds for all but that one.
    within = sorted(latencies)[:-1]
    assert max(within) <= ESTOP_WITHIN_MS, sorted(latencies)[-5:]
    assert max(latencies) <= ESTOP_OUTLIER_MS, sorted(latencies)[-5:]


def two_machines_together(srv: Server) -> tuple[str, str]:
    """Two new machines on one worker (placed by load: of three, two share one)."""
    ids = []
    for k in range(3):
        name = f"together{k}"
        assert srv.http.post("/api/machines", json={"id": name, "demo": True}).status_code == 201
        srv.wait_powered(name)
        ids.append(name)
    homes = [worker_of(srv, m)["id"] for m in ids]
    a, b = next((a, b) for a, b in itertools.combinations(range(3), 2) if homes[a] == homes[b])
    return ids[a], ids[b]


BOMB = "%L1\nG91 G01 X0.001 F100\nM17\n%MAIN\nG90\nL1 P{reps}\nM30\n"


def test_a_long_program_never_stalls_its_neighbours(srv: Server) -> None:
    """The probe's repetition bomb: 45 000 runs of a subprogram (90 000 blocks) take seconds to
    interpret.
    Interpreted in the loop it froze every machine of the worker (an emergency stop to a
    neighbour answered after 5 s); beside it, the neighbour's stops act as fast as ever.
    Beyond 100 000 blocks the load is refused where the main program makes it so long."""
    loader, neighbour = two_machines_together(srv)
    done: dict[str, httpx.Response] = {}

    def load() -> None:
        with httpx.Client(base_url=srv.base, headers=srv.auth, timeout=60) as c:
            body = {"type": "program_load", "name": "BOMB", "text": BOMB.format(reps=45_000)}
            done["r"] = c.post(f"/api/machines/{loader}/commands", json=body)

    thread = threading.Thread(target=load)
    thread.start()
    latencies: list[float] = []
    during = 0  # stops sent while the load was being interpreted (about a second)
    try:
        while thread.is_alive() or len(latencies) < 10:
            loading = thread.is_alive()
            r = srv.emergency_stop(neighbour)
            assert r.status_code == 200, r.text
            latencies.append(r.json()["latency_ms"])
            during += loading
            assert srv.command(neighbour, {"type": "reset"}).status_code == 200
            time.sleep(0.01)
    finally:
        thread.join(timeout=60)
    assert done["r"].status_code == 200, done["r"].text
    assert during >= 3  # stops were sent throughout the interpretation, however fast it was
    assert sorted(latencies)[len(latencies) // 2] <= ESTOP_WITHIN_MS
    assert max(latencies) <= ESTOP_OUTLIER_MS, sorted(latencies)[-5:]
    # the loaded program runs: cycle start answers at once (interpreted from here already)
    assert srv.command(loader, {"type": "cycle_start"}).status_code == 200
    assert srv.command(loader, {"type": "program_stop"}).status_code == 200
    too_long = {"type": "program_load", "name": "BOMB", "text": BOMB.format(reps=200_001)}
    r = srv.http.post(f"/api/machines/{neighbour}/commands", json=too_long, timeout=60)
    assert r.status_code == 422
    refusal = r.json()["detail"]
    assert (refusal["line"], refusal["column"]) == (6, 1)  # L1 P200001
    assert "more than 100000 blocks" in refusal["message"]


def test_worker_processes_run_one_blas_thread(srv: Server) -> None:
    """OpenBLAS' helper threads spin while they wait; beside a SCHED_FIFO loop on two cores
    they starved and one drive model's matrix exponential took a second of the loop."""
    for w in service(srv)["workers"]:
        raw = Path(f"/proc/{w['pid']}/environ").read_bytes()
        env = dict(kv.split(b"=", 1) for kv in raw.split(b"\0") if b"=" in kv)
        assert env.get(b"OPENBLAS_NUM_THREADS") == b"1", w
        threads = os.listdir(f"/proc/{w['pid']}/task")
        assert len(threads) < 8, threads  # the loop, the log and a few of Python's: no pool


def test_ctrl_c_stops_the_service_and_its_workers_quietly(tmp_path: Path) -> None:
    """Ctrl-C in a terminal reaches the whole process group (as systemd's stop reaches the
    whole unit): the service stops its workers in order, nothing is rebuilt, nothing prints
    a traceback, and no process of the group is left behind."""
    port = free_port()
    log = tmp_path / "service.log"
    cmd = [sys.executable, "-m", "backend.cli", "serve", "--port", str(port)]
    with log.open("w") as out:
        proc = subprocess.Popen(
            [*cmd, "--db", str(tmp_path / "db.sqlite")],
            cwd=ROOT,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # its own group, as a terminal's foreground job
        )
        try:
            deadline = time.monotonic() + 60  # a safety net, no measure
            while True:
                try:
                    if httpx.get(f"http://127.0.0.1:{port}/api/health").status_code == 200:
                        break
                except httpx.TransportError:
                    pass
                assert time.monotonic() < deadline, log.read_text()
                time.sleep(0.1)
            os.killpg(proc.pid, signal.SIGINT)
            proc.wait(timeout=30)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
    deadline = time.monotonic() + 10
    while True:  # its workers end with it (their socket closed)
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        assert time.monotonic() < deadline, "a process of the service outlived it"
        time.sleep(0.1)
    text = log.read_text()
    assert "Traceback" not in text and "is gone" not in text and "rebuilt" not in text, text
