"""The Rerun web viewer that rerun-sdk bundles, run on loopback and reached through the service.

The viewer has no authentication, so it listens on 127.0.0.1 only (its own HTTP port and the
gRPC port it also opens); the service forwards `/rerun/…` to it. It is started on first use,
with its own configuration folder in which its usage analytics are switched off.

It dies with the service, however the service ends (even `kill -9`): Linux sends it SIGKILL
when the thread that started it ends (PR_SET_PDEATHSIG), and that thread lives as long as the
service.
"""

from __future__ import annotations

import contextlib
import ctypes
import importlib.util
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from urllib.parse import quote

from fastapi import Request

from backend.errors import Unavailable


def viewer_url(request: Request, rrd_path: str) -> str:
    """The viewer page (through the service) that loads an .rrd the service serves."""
    base = str(request.base_url).rstrip("/")
    return f"/rerun/?hide_welcome_screen&url={quote(base + rrd_path, safe='')}"


_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
_libc = ctypes.CDLL(None, use_errno=True)  # loaded before any fork: the child only calls it


def _die_with(parent_pid: int) -> Callable[[], None]:
    """A `preexec_fn`: the child gets SIGKILL when the forking thread ends; if the parent is
    already gone (it died between fork and prctl), the child ends at once."""

    def arm() -> None:
        _libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        if os.getppid() != parent_pid:
            os.kill(os.getpid(), signal.SIGKILL)

    return arm


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def rerun_cli() -> str:
    """The `rerun` executable of this environment: the binary rerun-sdk ships (its `rerun`
    script would run it as a grandchild, out of reach of terminate)."""
    spec = importlib.util.find_spec("rerun_cli")
    if spec is not None and spec.origin is not None:
        binary = Path(spec.origin).with_name("rerun")
        if binary.exists():
            return str(binary)
    local = Path(sys.executable).with_name("rerun")
    return str(local) if local.exists() else (shutil.which("rerun") or "rerun")


class RerunViewer:
    """One viewer process for the service."""

    def __init__(self, log_path: Path) -> None:
        self.log_path = log_path
        self.home = log_path.parent / "rerun-home"  # XDG folders of the viewer process
        self.port: int | None = None
        self._proc: subprocess.Popen[bytes] | None = None
        self._lock = threading.Lock()
        # The parent-death signal fires when the forking *thread* ends, so the viewer is
        # started from this one thread, which stays (request threads come and go).
        self._spawner = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rerun-spawn")

    def ensure(self, timeout_s: float = 20.0) -> int:
        """The viewer's HTTP port on 127.0.0.1, starting it when needed."""
        with self._lock:
            if self._proc is not None and self._proc.poll() is None and self.port is not None:
                return self.port
            env = self._quiet_env()
            web, grpc = _free_port(), _free_port()
            cmd = [rerun_cli(), "--serve-web", "--bind", "127.0.0.1"]
            cmd += ["--web-viewer-port", str(web), "--port", str(grpc)]
            self.log_path.parent.mkdir(parents=True, exist_ok=True)
            with self.log_path.open("ab") as log:
                self._proc = self._spawner.submit(
                    subprocess.Popen,
                    cmd,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    stdin=subprocess.DEVNULL,
                    env=env,
                    start_new_session=True,  # its own process group: stop ends all of it
                    preexec_fn=_die_with(os.getpid()),
                ).result()
            deadline = time.monotonic() + timeout_s
            while time.monotonic() < deadline:
                if self._proc.poll() is not None:
                    break
                with (
                    contextlib.suppress(OSError),
                    socket.create_connection(("127.0.0.1", web), timeout=0.2),
                ):
                    self.port = web
                    return web
                time.sleep(0.1)
            self.stop_locked()
            msg = f"the Rerun viewer did not start (see {self.log_path})"
            raise Unavailable(msg)

    def analytics_config(self) -> Path:
        return self.home / "config" / "rerun" / "analytics.json"

    def _quiet_env(self) -> dict[str, str]:
        """Environment of the viewer: its own config and data folders, analytics off."""
        env = {
            **os.environ,
            "XDG_CONFIG_HOME": str(self.home / "config"),
            "XDG_DATA_HOME": str(self.home / "data"),
        }
        cfg = self.analytics_config()
        try:
            off = not json.loads(cfg.read_text())["analytics_enabled"]
        except (OSError, ValueError, KeyError):
            off = False
        if not off:
            subprocess.run(
                [rerun_cli(), "analytics", "disable"], env=env, capture_output=True, timeout=30
            )
        return env

    def stop(self) -> None:
        with self._lock:
            self.stop_locked()

    def stop_locked(self) -> None:
        if self._proc is not None and self._proc.poll() is None:
            os.killpg(self._proc.pid, signal.SIGTERM)
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(self._proc.pid, signal.SIGKILL)
                self._proc.wait(timeout=5)
        self._proc, self.port = None, None
