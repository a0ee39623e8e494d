"""Smoke test of the container image (`make image-test`): the image's own entrypoint and
command in a buildah working container, checked from outside over real HTTP and a real
websocket.

buildah's chroot isolation shares the host's network and process table, so the service is
started on a free loopback port (INBETRIEB_HOST and INBETRIEB_PORT, as an operator sets them)
with a fresh host folder as its volume, and stopped by SIGTERM to the server process itself,
as `docker stop` sends it to a container's PID 1. The steps: health, the image's HEALTHCHECK
command, the HMI and the shipped exercises served, the printed one-time login, a telemetry
websocket (with a ticket, as the browser opens it) carrying the spindle's speed while M3 S1000
spins it up, a parameter write, SIGTERM (exit 0, the store checkpointed), a second start on
the same volume, a login link from `inbetrieb user link` in the container, the parameter read
back, SIGTERM again.

Only the standard library, httpx and websockets (the service's own dependencies): the frame
format is decoded here as the API guide documents it, not by the service's code. Exit 0 when
every step passed, 1 at the first failure (with the service's output).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
from websockets.exceptions import WebSocketException
from websockets.sync.client import ClientConnection, connect

ROOT = Path(__file__).resolve().parents[1]
VOLUME = "/var/lib/inbetrieb"  # the image's VOLUME: the store and its traces
MACHINE = "demo"  # the demo lathe a fresh store creates
SPEED_RPM = 1000.0
SPEED_BAND = 0.1  # "speed reached": within ±10 % (the demo spindle's vb_prozent)
PARAM = ("axis", "X", "getriebe[0].kv")  # position loop gain, 0.01/s; applies at once
PARAM_VALUE = 1234
START_TIMEOUT_S = 180.0  # a safety net: on a CPU of another model numba compiles once more
STOP_TIMEOUT_S = 20.0
LINK = re.compile(r"Log in as (\S+) \(once, within an hour\): (\S+)")


class Failed(Exception):
    """A step did not pass: its message says what was expected and what came."""


def step(name: str, figure: str) -> None:
    print(f"ok  {name}: {figure}", flush=True)


def buildah(*args: str, timeout_s: float = 120.0) -> str:
    done = subprocess.run(
        ["buildah", *args], capture_output=True, text=True, timeout=timeout_s, check=False
    )
    if done.returncode != 0:
        raise Failed(f"buildah {' '.join(args)}: exit {done.returncode}: {done.stderr.strip()}")
    return done.stdout


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def children(pid: int) -> list[int]:
    """Every process below `pid` (chroot isolation: they are the host's processes)."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, ValueError, IndexError):
            fields = stat.read_text().rsplit(")", 1)[1].split()
            parents.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def parent(pid: int) -> int:
    """The parent process' pid (0 once `pid` is gone)."""
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return 0


def cmdline(pid: int) -> list[str]:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")[:-1]
    except OSError:
        return []


def uid_of(pid: int) -> int:
    """The process' real uid."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Uid:"):
            return int(line.split()[1])
    raise Failed(f"no uid of process {pid}")


@dataclass
class Image:
    """What the smoke takes from the image's configuration (as docker and podman run it)."""

    name: str
    entrypoint: list[str]
    cmd: list[str]
    user: str
    healthcheck: list[str]
    volumes: list[str]
    size: str

    @classmethod
    def inspect(cls, name: str) -> Image:
        config: dict[str, Any] = json.loads(buildah("inspect", "--type", "image", name))
        docker = config["Docker"]["config"]
        test = (docker.get("Healthcheck") or {}).get("Test") or []
        size = buildah("images", "--format", "{{.Size}}", name).strip()
        return cls(
            name,
            docker.get("Entrypoint") or [],
            docker.get("Cmd") or [],
            docker.get("User") or "root",
            test[1:] if test[:1] == ["CMD"] else [],
            sorted(docker.get("Volumes") or {}),
            size,
        )


@dataclass
class Service:
    """One run of the image's entrypoint and command in the working container."""

    container: str
    image: Image
    volume: Path
    port: int
    proc: subprocess.Popen[str] | None = None
    output: list[str] = field(default_factory=list)
    _reader: threading.Thread | None = None

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def env(self) -> list[str]:
        return ["--env", "INBETRIEB_HOST=127.0.0.1", "--env", f"INBETRIEB_PORT={self.port}"]

    def start(self) -> float:
        """Start it; the seconds until /api/health answers 200."""
        cmd = ["buildah", "run", "--isolation", "chroot", *self.env()]
        cmd += ["--volume", f"{self.volume}:{VOLUME}", self.container, "--"]
        cmd += [*self.image.entrypoint, *self.image.cmd]
        t0 = time.monotonic()
        self.proc = subprocess.Popen(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        while time.monotonic() - t0 < START_TIMEOUT_S:
            if self.proc.poll() is not None:
                raise Failed(f"the service ended at start (exit {self.proc.returncode})")
            with contextlib.suppress(httpx.TransportError):
                if httpx.get(f"{self.base}/api/health", timeout=2).status_code == 200:
                    return time.monotonic() - t0
            time.sleep(0.1)
        raise Failed(f"no answer from /api/health within {START_TIMEOUT_S:.0f} s")

    def _read(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        for line in self.proc.stdout:
            self.output.append(line.rstrip("\n"))

    def server_pid(self) -> int:
        """The server process: what `docker stop` signals (the container's PID 1)."""
        assert self.proc is not None
        entry = self.image.entrypoint[-1]
        # the console script runs as `python /opt/inbetrieb/bin/inbetrieb serve`, below
        # buildah's own `buildah-chroot-exec /opt/inbetrieb/bin/inbetrieb serve`; its worker
        # zygote and the workers are forks of it, with its command line, below it
        serving = [
            p
            for p in children(self.proc.pid)
            if (argv := cmdline(p))[1:3] == [entry, "serve"] and "buildah" not in argv[0]
        ]
        found = [p for p in serving if parent(p) not in serving]
        if len(found) != 1:
            raise Failed(f"expected one server process below buildah run, found {found}")
        return found[0]

    def login_link(self, timeout_s: float = 10.0) -> tuple[str, str]:
        """The user and the one-time link the service printed at start (on loopback)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            for line in self.output:
                if m := LINK.search(line):
                    return m[1], m[2]
            time.sleep(0.05)
        raise Failed("the service printed no login link")

    def stop(self) -> tuple[float, int]:
        """SIGTERM to the server; the seconds until buildah run ended, and its exit code."""
        assert self.proc is not None
        pid = self.server_pid()
        t0 = time.monotonic()
        os.kill(pid, signal.SIGTERM)
        try:
            rc = self.proc.wait(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            raise Failed(f"still running {STOP_TIMEOUT_S:.0f} s after SIGTERM") from None
        seconds = time.monotonic() - t0
        if self._reader is not None:
            self._reader.join(timeout=5)
        self.proc = None
        return seconds, rc

    def kill(self) -> None:
        """After a failure: nothing of this run is left behind. SIGTERM first, so the
        service removes its rings from the host's /dev/shm; SIGKILL what is left after that."""
        if self.proc is None:
            return
        with contextlib.suppress(Failed, ProcessLookupError, subprocess.TimeoutExpired):
            os.kill(self.server_pid(), signal.SIGTERM)
            self.proc.wait(timeout=STOP_TIMEOUT_S)
        if self.proc.poll() is None:
            for pid in reversed([self.proc.pid, *children(self.proc.pid)]):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            self.proc.wait(timeout=10)
        self.proc = None


def session(base: str, link: str) -> httpx.Client:
    """A browser-like client logged in by a one-time link (session and CSRF cookies)."""
    client = httpx.Client(base_url=base, timeout=10)
    first = client.get(link.replace("localhost", "127.0.0.1"), follow_redirects=False)
    if first.status_code != 303:
        raise Failed(f"the login link answered {first.status_code}, not 303: {first.text[:200]}")
    csrf = client.cookies.get("inbetrieb_csrf")
    if not csrf:
        raise Failed("the login set no CSRF cookie")
    client.headers["X-CSRF-Token"] = csrf  # the page echoes it on every state change
    return client


def check(response: httpx.Response, status: int = 200) -> Any:
    if response.status_code != status:
        raise Failed(
            f"{response.request.method} {response.request.url.path}: "
            f"{response.status_code}, not {status}: {response.text[:300]}"
        )
    return response.json() if response.content else None


def decode_frame(buf: bytes) -> tuple[dict[str, Any], list[list[float]]]:
    """`INBT`, a little-endian u32 header length, the JSON header, then float64 samples
    signal by signal (the API guide's telemetry frame)."""
    if buf[:4] != b"INBT":
        raise Failed(f"a binary message that is no frame: {buf[:8]!r}")
    (n,) = struct.unpack_from("<I", buf, 4)
    header: dict[str, Any] = json.loads(buf[8 : 8 + n])
    count = int(header["count"])
    values = struct.unpack_from(f"<{count * len(header['signals'])}d", buf, 8 + n)
    return header, [
        list(values[i * count : (i + 1) * count]) for i in range(len(header["signals"]))
    ]


@dataclass
class Telemetry:
    """What arrived on the telemetry websocket."""

    frames: int = 0
    samples: int = 0  # per signal
    gaps: int = 0  # frames that did not start where the one before ended
    next_cycle: int | None = None


def spindle_and_telemetry(base: str, client: httpx.Client) -> None:
    ticket = check(client.post("/api/auth/ws-ticket"))["ticket"]
    url = base.replace("http", "ws", 1) + f"/api/machines/{MACHINE}/telemetry?ticket={ticket}"
    signals = ["S1.speed_cmd_rpm", "S1.speed_act_rpm"]
    seen = Telemetry()
    with connect(url, open_timeout=10, max_size=None) as ws:
        hello = json.loads(_recv(ws, text=True))
        if hello.get("type") != "hello" or not set(signals) <= {
            s["name"] for s in hello.get("signals", [])
        }:
            raise Failed(f"no hello with {signals}: {str(hello)[:200]}")
        ws.send(json.dumps({"type": "subscribe", "signals": signals, "max_rate_hz": None}))
        _frame(ws, signals, seen)  # frames flow before anything moves
        t0 = time.monotonic()
        done = check(
            client.post(
                f"/api/machines/{MACHINE}/commands",
                json={"type": "mdi", "block": f"M3 S{SPEED_RPM:.0f}"},
            )
        )
        command_cycle = int(done["cycle"])
        # the first cycle the actual speed is within the band, and the first the command's
        # ramp has arrived at the speed programmed
        reached: int | None = None
        ramped: int | None = None
        cycle_s = 0.001
        peak = 0.0
        while reached is None or ramped is None:
            if time.monotonic() - t0 > 15:
                raise Failed(f"S1 not at {SPEED_RPM:.0f} rpm within 15 s (peak {peak:.0f} rpm)")
            header, (cmd, act) = _frame(ws, signals, seen)
            cycle_s = float(header["cycle_s"])
            for i, (c, v) in enumerate(zip(cmd, act, strict=True)):
                cycle = int(header["first_cycle"]) + i * int(header["stride"])
                if cycle < command_cycle:
                    continue
                peak = max(peak, v)
                if reached is None and abs(v - SPEED_RPM) <= SPEED_BAND * SPEED_RPM:
                    reached = cycle
                if ramped is None and abs(c - SPEED_RPM) < 1e-6:
                    ramped = cycle
        wall_s = time.monotonic() - t0
        for _ in range(10):  # a fifth of a second more: the frames keep coming
            _frame(ws, signals, seen)
    axes = check(client.get(f"/api/machines/{MACHINE}/status"))["axes"]
    s1 = next(a for a in axes if a["name"] == "S1")
    if not s1["speed_reached"]:
        raise Failed(f"the status says S1 has not reached its speed: {s1}")
    step(
        "spindle",
        f"M3 S{SPEED_RPM:.0f} accepted at cycle {command_cycle}; S1 within ±10 % of "
        f"{SPEED_RPM:.0f} rpm {(reached - command_cycle) * cycle_s:.2f} s later, its command at "
        f"{SPEED_RPM:.0f} "
        f"after {(ramped - command_cycle) * cycle_s:.2f} s (simulated time, from telemetry; "
        f"{wall_s:.2f} s wall), then status speed_reached at {s1['vel_act']:.1f} rpm",
    )
    step(
        "telemetry",
        f"{seen.frames} frames, {seen.samples} samples of each of {len(signals)} signals, "
        f"{seen.gaps} gaps (ticket from the session, as the HMI opens it)",
    )
    check(client.post(f"/api/machines/{MACHINE}/commands", json={"type": "spindle", "m": 5}))


def _recv(ws: ClientConnection, text: bool) -> str | bytes:
    """The next message of that kind (JSON messages between frames are status and events)."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        msg = ws.recv(timeout=10)
        if isinstance(msg, str) == text:
            return msg
    raise Failed("no message within 10 s")


def _frame(
    ws: ClientConnection, signals: list[str], seen: Telemetry
) -> tuple[dict[str, Any], list[list[float]]]:
    msg = _recv(ws, text=False)
    assert isinstance(msg, bytes)
    header, columns = decode_frame(msg)
    if header["signals"] != signals or header["count"] < 1:
        raise Failed(f"a frame without the subscribed samples: {header}")
    first = int(header["first_cycle"])
    if seen.next_cycle is not None and first != seen.next_cycle:
        seen.gaps += 1
    seen.next_cycle = first + int(header["count"]) * int(header["stride"])
    seen.frames += 1
    seen.samples += int(header["count"])
    return header, columns


def read_param(client: httpx.Client) -> dict[str, Any]:
    scope, target, name = PARAM
    values = check(
        client.get(f"/api/machines/{MACHINE}/parameters", params={"scope": scope, "target": target})
    )
    return next(p for p in values if p["name"] == name)


def write_param(client: httpx.Client) -> None:
    before = read_param(client)
    scope, target, name = PARAM
    change = {"scope": scope, "target": target, "name": name, "value": PARAM_VALUE}
    change["base_version"] = before["version"]
    written = check(client.patch(f"/api/machines/{MACHINE}/parameters", json={"changes": [change]}))
    new = written["changes"][0]
    if (new["new"], new["pending"]) != (PARAM_VALUE, False):
        raise Failed(f"the write came back as {new}")
    step("parameter", f"{target} {name} {before['value']} -> {PARAM_VALUE} written (applies now)")


def stopped(service: Service) -> None:
    seconds, rc = service.stop()
    if rc != 0:
        raise Failed(f"exit {rc} after SIGTERM, not 0")
    if "Inbetrieb stopped" not in service.output:
        raise Failed("no 'Inbetrieb stopped' after SIGTERM")
    wal = service.volume / "inbetrieb.sqlite-wal"
    wal_bytes = wal.stat().st_size if wal.exists() else 0
    if wal_bytes:
        raise Failed(f"the store's WAL holds {wal_bytes} bytes after the stop: not checkpointed")
    store = (service.volume / "inbetrieb.sqlite").stat().st_size
    step(
        "stop",
        f"SIGTERM to the server -> exit 0 in {seconds:.2f} s, 'Inbetrieb stopped', "
        f"WAL {'empty' if wal.exists() else 'gone'} (checkpointed), store {store / 1024:.0f} KiB",
    )


def first_run(service: Service, image: Image) -> None:
    seconds = service.start()
    pid = service.server_pid()
    uid = uid_of(pid)
    if uid == 0:
        raise Failed("the server runs as root")
    step("start", f"/api/health 200 after {seconds:.1f} s (fresh volume; server uid {uid})")
    t0 = time.monotonic()
    # the image's HEALTHCHECK command as docker runs it: in the container, beside the server
    probe = ["buildah", "run", "--isolation", "chroot", *service.env(), service.container]
    hc = subprocess.run(
        [*probe, "--", *image.healthcheck],
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )
    if hc.returncode != 0:
        raise Failed(f"the HEALTHCHECK command exited {hc.returncode}: {hc.stderr.strip()}")
    step("healthcheck", f"{' '.join(image.healthcheck)} -> 0 in {time.monotonic() - t0:.1f} s")
    user, link = service.login_link()
    with contextlib.closing(session(service.base, link)) as client:
        me = check(client.get("/api/auth/me"))
        if me["name"] != user:
            raise Failed(f"logged in as {me['name']}, the link was for {user}")
        with httpx.Client(base_url=service.base, timeout=10) as other:
            again = other.get(link.replace("localhost", "127.0.0.1"), follow_redirects=False)
        if again.status_code != 401:
            raise Failed(f"the login link worked twice ({again.status_code})")
        step(
            "login",
            f"the printed one-time link: a session as {me['name']} ({me['role']}); again: 401",
        )
        page = client.get("/")
        if page.status_code != 200 or "<script" not in page.text:
            raise Failed(f"GET / is no HMI page: {page.status_code} {page.text[:200]}")
        shipped = sorted(p.stem for p in (ROOT / "exercises").glob("*.toml"))
        listed = sorted(e["id"] for e in check(client.get("/api/exercises")))
        if not set(shipped) <= set(listed):
            raise Failed(f"exercises {listed}, shipped {shipped}")
        step(
            "HMI",
            f"GET / serves the built HMI ({len(page.text)} bytes); {len(listed)} exercises listed",
        )
        spindle_and_telemetry(service.base, client)
        write_param(client)
    stopped(service)


def second_run(service: Service) -> None:
    seconds = service.start()
    step("restart", f"/api/health 200 after {seconds:.1f} s on the same volume")
    # a second process in the same working container, on the same store: as `docker exec`
    printed = buildah(
        "run",
        "--isolation",
        "chroot",
        "--volume",
        f"{service.volume}:{VOLUME}",
        service.container,
        "--",
        service.image.entrypoint[0],
        "user",
        "link",
        "admin",
        "--url",
        service.base,
    ).strip()
    with contextlib.closing(session(service.base, printed)) as client:
        check(client.get("/api/auth/me"))
        step("user link", "`inbetrieb user link admin` in the container: its link logs in")
        got = read_param(client)
        if got["value"] != PARAM_VALUE:
            raise Failed(f"{PARAM[2]} is {got['value']} after the restart, not {PARAM_VALUE}")
        step("persisted", f"{PARAM[1]} {PARAM[2]} = {got['value']} after the restart")
    stopped(service)


@contextlib.contextmanager
def working_container(image: str) -> Iterator[str]:
    name = f"inbetrieb-smoke-{os.getpid()}"
    buildah("from", "--name", name, image)
    try:
        yield name
    finally:
        subprocess.run(["buildah", "rm", name], capture_output=True, check=False)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--image", required=True, help="e.g. localhost/inbetrieb:0.2.0")
    args = parser.parse_args(argv)
    t0 = time.monotonic()
    services: list[Service] = []
    volume = Path(tempfile.mkdtemp(prefix="inbetrieb-smoke-"))
    try:
        image = Image.inspect(args.image)
        if VOLUME not in image.volumes or not image.healthcheck or not image.entrypoint:
            raise Failed(f"the image lacks its volume, healthcheck or entrypoint: {image}")
        print(
            f"image {image.name} ({image.size}): {' '.join(image.entrypoint + image.cmd)}, "
            f"user {image.user}",
            flush=True,
        )
        with working_container(image.name) as container:
            try:
                uid = int(buildah("run", "--isolation", "chroot", container, "--", "id", "-u"))
                if uid == 0:
                    raise Failed(f"the image's user {image.user} is root")
                os.chown(volume, uid, uid)  # as an operator prepares a host folder for it
                services.append(Service(container, image, volume, free_port()))
                first_run(services[-1], image)
                services.append(Service(container, image, volume, free_port()))
                second_run(services[-1])
            finally:  # before the working container goes
                for service in services:
                    service.kill()
    except (Failed, httpx.HTTPError, WebSocketException, OSError, TimeoutError) as e:
        print(f"FAIL {type(e).__name__}: {e}", flush=True)
        if services:
            print("--- the service's output ---", *services[-1].output[-60:], sep="\n")
        return 1
    finally:
        shutil.rmtree(volume, ignore_errors=True)
    print(f"smoke passed in {time.monotonic() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
