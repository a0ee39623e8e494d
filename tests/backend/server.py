"""A real service for integration tests: `inbetrieb serve` in a process of its own on a free
port."""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import socket
import tempfile
import time
from pathlib import Path
from typing import IO, Any

import httpx

from api.auth import Role
from backend.services.accounts import Accounts
from backend.services.store import Store
from tests.backend.forked import ForkedService

ROOT = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


USER, PASSWORD = "tester", "tester-password"  # an admin in every test store


_template: Path | None = None


def _store_with_the_admin() -> Path:
    """A store with the test admin, made once per test process and copied for each new service:
    hashing the password (argon2) costs a tenth of a second of a core, and a run starts
    about 140 services."""
    global _template
    if _template is None:
        folder = Path(tempfile.mkdtemp(prefix="inbetrieb-admin-"))
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        store = Store(folder / "admin.sqlite")
        try:
            Accounts(store).add_user(USER, Role.ADMIN, PASSWORD)
        finally:
            store.close()  # one file: its write-ahead log folded in
        _template = folder / "admin.sqlite"
    return _template


def seed_user(db: Path) -> str:
    """The test admin in the store (added once) and a fresh API token of theirs."""
    if not db.exists():
        db.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(_store_with_the_admin(), db)
    store = Store(db)
    try:
        accounts = Accounts(store)
        if all(u.name != USER for u in accounts.users()):
            accounts.add_user(USER, Role.ADMIN, PASSWORD)
        return accounts.new_token(USER, "tests")
    finally:
        store.close()


OTHERS_PASSWORD = "a long password"


def add_users(db: Path, users: dict[str, Role]) -> dict[str, str]:
    """More users in the store (password OTHERS_PASSWORD), with an API token each: the
    tokens by name."""
    store = Store(db)
    try:
        accounts = Accounts(store)
        for name, role in users.items():
            accounts.add_user(name, role, OTHERS_PASSWORD)
        return {name: accounts.new_token(name) for name in users}
    finally:
        store.close()


def bearer(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}"}


class Server:
    """One `inbetrieb serve` process (tests/backend/forked.py) serving the app with its own
    SQLite file."""

    def __init__(
        self,
        db: Path,
        *extra: str,
        env: dict[str, str] | None = None,
        seed: bool = True,
    ) -> None:
        self.seed = seed  # the test admin and a token of theirs in the store before start
        self.db = db
        # one worker process unless the test is about several (`--workers` among `extra`
        # wins): a test drives a machine or two, and a worker's start (its interpreter, numba,
        # the kernel's warm-up) is the larger part of a service's
        self.extra = extra if "--workers" in extra else (*extra, "--workers", "1")
        self.env = env or {}  # INBETRIEB_* settings
        self.port = free_port()
        self.base = f"http://127.0.0.1:{self.port}"
        self.ws_base = f"ws://127.0.0.1:{self.port}"
        self.proc: ForkedService | None = None
        self.token = ""
        self.http = httpx.Client(base_url=self.base, timeout=10)

    @property
    def auth(self) -> dict[str, str]:
        """The test user's API token as a request header."""
        return {"Authorization": f"Bearer {self.token}"}

    @property
    def ws_auth(self) -> dict[str, Any]:
        """`connect(url, **srv.ws_auth)`: a websocket with the test user's API token."""
        return {"additional_headers": self.auth}

    @property
    def auth_header(self) -> str:
        """The token as a raw HTTP header line (CRLF included)."""
        return f"Authorization: Bearer {self.token}\r\n"

    def start(self, stdout: IO[str] | None = None, timeout_s: float = 60.0) -> Server:
        """Start the service; wait until it answers (`timeout_s`: a safety net, no measure).
        `stdout` takes what it prints, its log included."""
        if self.seed:
            self.token = seed_user(self.db)
            self.http.headers["Authorization"] = f"Bearer {self.token}"
        argv = ["serve", "--port", str(self.port), "--db", str(self.db), *self.extra]
        out = 1 if stdout is None else stdout.fileno()
        self.proc = ForkedService(
            argv,
            env={**os.environ, "PYTHONUNBUFFERED": "1", **self.env},
            cwd=ROOT,
            stdout=out,
            stderr=2 if stdout is None else out,  # the log with it
        )
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                if self.http.get("/api/health").status_code == 200:
                    return self
            except httpx.TransportError:
                time.sleep(0.1)
        self.proc.kill()  # not left running (nor its Popen unwaited) behind the failed test
        self.proc.wait()
        self.proc = None
        raise RuntimeError("service did not come up")

    def stop(self) -> None:
        if self.proc is not None:
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(timeout=20)
            self.proc = None

    def close(self) -> None:
        self.http.close()  # first: an open TLS keep-alive connection holds up the shutdown
        self.stop()

    # --- helpers ----------------------------------------------------------------------------
    def command(self, mid: str, body: dict[str, Any]) -> httpx.Response:
        return self.http.post(f"/api/machines/{mid}/commands", json=body)

    def emergency_stop(self, mid: str) -> httpx.Response:
        return self.http.post(f"/api/machines/{mid}/emergency-stop")

    def status(self, mid: str = "demo") -> dict[str, Any]:
        r = self.http.get(f"/api/machines/{mid}/status")
        r.raise_for_status()
        data: dict[str, Any] = r.json()
        return data

    def axis(self, name: str, mid: str = "demo") -> dict[str, Any]:
        return next(a for a in self.status(mid)["axes"] if a["name"] == name)

    def wait_powered(self, mid: str, timeout_s: float = 10.0) -> None:
        """Wait until the machine's PLC has switched its drives on (real-time pacing)."""
        deadline = time.monotonic() + timeout_s
        while not self.status(mid)["plc"]["drives_powered"]:
            if time.monotonic() > deadline:
                raise AssertionError(f"{mid}: drives not powered")
            time.sleep(0.05)

    def pace(self, mid: str, **body: Any) -> dict[str, Any]:
        r = self.http.post(f"/api/machines/{mid}/simulation", json=body)
        r.raise_for_status()
        data: dict[str, Any] = r.json()
        return data

    def step(self, mid: str, cycles: int) -> dict[str, Any]:
        r = self.http.post(f"/api/machines/{mid}/simulation/step", json={"cycles": cycles})
        r.raise_for_status()
        data: dict[str, Any] = r.json()
        return data
