"""The systemd install (deploy/systemd): install.sh into a temporary root, then the unit's own
`ExecStart=` line with its environment started by hand, over real HTTP, and stopped as
systemd stops it (SIGTERM to the main process).

Fast and offline: the venv is made without pip (the test's pip runs in it), and the package
comes from a wheelhouse holding one wheel of this checkout made here, an editable one (a
`.pth` naming the checkout, and the test's own site-packages for the dependencies, as PEP 660
editable wheels do), so install.sh's offline path (`--wheelhouse`) runs as an operator's would,
without building or downloading anything.
"""

from __future__ import annotations

import base64
import hashlib
import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import time
import tomllib
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import psutil
import pytest

from backend.settings import Settings
from tests.backend.server import free_port
from tests.deploy.checks import env_file

ROOT = Path(__file__).resolve().parents[2]
UNIT = ROOT / "deploy" / "systemd" / "inbetrieb.service"
INSTALL = ROOT / "deploy" / "systemd" / "install.sh"
# where the unit and the installer put things: rebased under the temporary root
PREFIXES = ("/opt/inbetrieb", "/etc/inbetrieb", "/var/lib/inbetrieb", "/var/cache/inbetrieb")
HMI_MARK = "deploy-test HMI"


def parse_unit(text: str) -> dict[str, list[tuple[str, str]]]:
    """A unit file's sections as (key, value) pairs in order (keys repeat: Environment=)."""
    sections: dict[str, list[tuple[str, str]]] = {}
    current: list[tuple[str, str]] | None = None
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith(("#", ";")):
            continue
        if line.startswith("[") and line.endswith("]"):
            current = sections.setdefault(line[1:-1], [])
            continue
        assert current is not None and "=" in line, f"line {n}: {raw!r}"
        key, value = line.split("=", 1)
        current.append((key.strip(), value.strip()))
    return sections


def values(unit: dict[str, list[tuple[str, str]]], section: str, key: str) -> list[str]:
    return [v for k, v in unit.get(section, []) if k == key]


def editable_wheel(dest: Path) -> Path:
    """A wheel of this checkout that installs the `inbetrieb` command and a `.pth` naming the
    checkout and this interpreter's site-packages (the dependencies)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    name, version = project["name"], project["version"]
    info = f"{name}-{version}.dist-info"
    scripts = "".join(f"{k} = {v}\n" for k, v in project["scripts"].items())
    files = {
        f"__editable__.{name}-{version}.pth": f"{ROOT}\n{sysconfig.get_paths()['purelib']}\n",
        f"{info}/METADATA": f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n",
        f"{info}/WHEEL": "Wheel-Version: 1.0\nGenerator: tests.deploy\n"
        "Root-Is-Purelib: true\nTag: py3-none-any\n",
        f"{info}/entry_points.txt": f"[console_scripts]\n{scripts}",
    }
    record = []
    for path, text in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(text.encode()).digest()).rstrip(b"=")
        record.append(f"{path},sha256={digest.decode()},{len(text.encode())}")
    record.append(f"{info}/RECORD,,")
    files[f"{info}/RECORD"] = "\n".join(record) + "\n"
    wheel = dest / f"{name}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        for path, text in files.items():
            z.writestr(path, text)
    return wheel


@dataclass
class Install:
    root: Path
    wheelhouse: Path
    frontend: Path
    log: str

    def path(self, system_path: str) -> Path:
        return self.root / system_path.lstrip("/")

    def rebase(self, text: str) -> str:
        """The unit's system paths as they are under the temporary root."""
        for prefix in PREFIXES:
            text = re.sub(
                rf"(?<![\w/]){re.escape(prefix)}(?=/|\b|$)", str(self.root) + prefix, text
            )
        return text

    def run(self) -> str:
        """install.sh as an operator runs it offline, under the temporary root."""
        env = {
            **os.environ,
            # the venv without pip: the test's own pip runs in it (saves ensurepip's seconds)
            "PYTHONPATH": sysconfig.get_paths()["purelib"],
            "VENV_ARGS": "--without-pip",
            "PIP_ARGS": "--no-deps",  # the dependencies are the test's (the wheel's .pth)
        }
        r = subprocess.run(
            [
                *(str(INSTALL), "--root", str(self.root), "--python", sys.executable),
                *("--wheelhouse", str(self.wheelhouse), "--frontend", str(self.frontend)),
            ],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert r.returncode == 0, r.stdout + r.stderr
        return r.stdout + r.stderr


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Install:
    base = tmp_path_factory.mktemp("systemd")
    wheelhouse, frontend = base / "wheelhouse", base / "frontend"
    wheelhouse.mkdir()
    frontend.mkdir()
    editable_wheel(wheelhouse)
    shutil.copy(ROOT / "constraints.txt", wheelhouse)
    (frontend / "index.html").write_text(f"<!doctype html><title>{HMI_MARK}</title>\n")
    inst = Install(base / "root", wheelhouse, frontend, "")
    inst.log = inst.run()
    return inst


def test_the_install_lays_out_venv_hmi_exercises_store_settings_and_unit(
    installed: Install,
) -> None:
    assert os.access(installed.path("/opt/inbetrieb/bin/inbetrieb"), os.X_OK)
    assert (installed.path("/opt/inbetrieb/share/frontend/index.html")).read_text().count(HMI_MARK)
    shipped = sorted(p.name for p in (ROOT / "exercises").glob("*.toml"))
    assert shipped
    assert sorted(p.name for p in installed.path("/opt/inbetrieb/share/exercises").glob("*.toml"))
    assert installed.path("/var/lib/inbetrieb").is_dir()
    assert installed.path("/var/cache/inbetrieb/numba").is_dir()
    unit = installed.path("/etc/systemd/system/inbetrieb.service")
    assert unit.read_text() == UNIT.read_text()
    env = installed.path("/etc/inbetrieb/inbetrieb.env")
    assert env_file(env) == {}, "every setting starts commented out"
    assert oct(env.stat().st_mode & 0o777) == "0o640"
    assert "systemd not told" in installed.log  # no systemctl under a staging root


def test_the_settings_file_names_only_real_settings_with_valid_examples(
    installed: Install,
) -> None:
    """Uncommenting any line of the written settings file gives a valid setting."""
    text = installed.path("/etc/inbetrieb/inbetrieb.env").read_text()
    examples = re.findall(r"^#(INBETRIEB_\w+)=(.*)$", text, re.M)
    assert len(examples) >= 10
    for key, value in examples:
        field = key.removeprefix("INBETRIEB_").lower()
        assert field in Settings.model_fields, key
        Settings.model_validate({field: value})


def test_an_upgrade_keeps_the_settings_and_replaces_the_hmi(installed: Install) -> None:
    env = installed.path("/etc/inbetrieb/inbetrieb.env")
    env.write_text(env.read_text() + "INBETRIEB_WORKERS=3\n")
    stale = installed.path("/opt/inbetrieb/share/frontend/assets-of-the-old-build.js")
    stale.write_text("old")
    numba_stale = installed.path("/var/cache/inbetrieb/numba/old.nbi")
    numba_stale.write_text("old")
    installed.run()
    assert env_file(env) == {"INBETRIEB_WORKERS": "3"}
    assert not stale.exists()
    assert not numba_stale.exists(), "an upgrade drops the compiled kernel (a changed callee)"
    assert os.access(installed.path("/opt/inbetrieb/bin/inbetrieb"), os.X_OK)
    env.write_text(env.read_text().replace("INBETRIEB_WORKERS=3\n", ""))


def test_the_unit_runs_the_installed_command_as_its_user_hardened() -> None:
    unit = parse_unit(UNIT.read_text())
    svc = dict(unit["Service"])  # the last of repeated keys, as systemd takes single ones
    assert svc["ExecStart"].split() == ["/opt/inbetrieb/bin/inbetrieb", "serve"]
    assert svc["User"] == svc["Group"] == "inbetrieb"
    assert svc["WorkingDirectory"] == "/var/lib/inbetrieb"
    # systemd expands no glob in EnvironmentFile=: one fixed file, optional
    assert values(unit, "Service", "EnvironmentFile") == ["-/etc/inbetrieb/inbetrieb.env"]
    assert svc["KillSignal"] == "SIGTERM" and svc["KillMode"] == "mixed"
    assert int(svc["TimeoutStopSec"]) >= 10
    assert svc["Restart"] == "on-failure"
    for key in ("NoNewPrivileges", "ProtectHome", "PrivateTmp", "PrivateDevices"):
        assert svc[key] == "yes", key
    assert svc["ProtectSystem"] == "strict"
    assert "/var/lib/inbetrieb" in svc["ReadWritePaths"].split()
    assert svc["StateDirectory"] == "inbetrieb" and svc["CacheDirectory"] == "inbetrieb"
    # numba's JIT writes code pages; the workers' loops ask for SCHED_FIFO 10
    assert "MemoryDenyWriteExecute" not in svc and "RestrictRealtime" not in svc
    assert svc["LimitRTPRIO"] == "10"
    env = dict(v.split("=", 1) for v in values(unit, "Service", "Environment"))
    assert env["NUMBA_CACHE_DIR"].startswith("/var/cache/inbetrieb/")
    assert unit["Install"] == [("WantedBy", "multi-user.target")]


def systemd_analyze(*args: str) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("systemd-analyze")
    if exe is None:
        pytest.skip("systemd-analyze is not installed")
    return subprocess.run([exe, *args], capture_output=True, text=True, timeout=30)


def verify(unit_text: str, installed: Install, tmp_path: Path) -> str:
    """`systemd-analyze verify` of the unit, its command rebased to the temporary root (it
    checks that the command is executable): its complaints, '' when none."""
    copy = tmp_path / "inbetrieb.service"
    copy.write_text(installed.rebase(unit_text))
    r = systemd_analyze("verify", "--man=no", str(copy))
    return (r.stdout + r.stderr).strip() + ("" if r.returncode == 0 else f" (exit {r.returncode})")


def test_systemd_analyze_verifies_the_unit(installed: Install, tmp_path: Path) -> None:
    assert verify(UNIT.read_text(), installed, tmp_path) == ""


def test_systemd_analyze_names_a_misspelt_key(installed: Install, tmp_path: Path) -> None:
    """An unknown key is only a warning to systemd (the unit still loads, unhardened): the
    check above counts any complaint, so a typo fails it."""
    wrong = UNIT.read_text().replace("ProtectHome=yes", "ProtectHom=yes")
    assert "Unknown key 'ProtectHom'" in verify(wrong, installed, tmp_path)


def test_the_units_exposure_is_low() -> None:
    """systemd's own rating of the hardening: 'OK' is up to 4.9 of 10; we keep under 2.5."""
    r = systemd_analyze("security", "--offline=true", "--threshold=25", str(UNIT))
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr
    level = re.search(r"Overall exposure level for inbetrieb\.service: ([\d.]+)", r.stdout)
    assert level and float(level.group(1)) <= 2.5, r.stdout[-500:]


@pytest.fixture
def started(installed: Install) -> Iterator[tuple[subprocess.Popen[bytes], int]]:
    """The unit's ExecStart= with its Environment= lines and environment file, in its
    WorkingDirectory, with a clean environment as systemd gives it."""
    unit = parse_unit(installed.rebase(UNIT.read_text()))
    svc = dict(unit["Service"])
    port = free_port()
    settings = installed.path("/etc/inbetrieb/inbetrieb.env")
    original = settings.read_text()
    # what an operator writes in the settings file; and, for this test, the checkout's own
    # numba cache (the editable install runs the checkout's kernel, which the other tests
    # compiled there: an empty NUMBA_CACHE_DIR is numba's default)
    settings.write_text(
        original + f"INBETRIEB_PORT={port}\nINBETRIEB_DEMO=false\nINBETRIEB_WORKERS=1\n"
        "NUMBA_CACHE_DIR=\n"
    )
    env = {"PATH": "/usr/local/bin:/usr/bin:/bin", "LANG": "C.UTF-8"}
    env["HOME"] = svc["WorkingDirectory"]  # the system user's home
    for assignment in values(unit, "Service", "Environment"):
        key, value = assignment.split("=", 1)
        env[key] = value
    (path,) = (v.lstrip("-") for v in values(unit, "Service", "EnvironmentFile"))
    env.update(env_file(Path(path)))
    proc = subprocess.Popen(
        svc["ExecStart"].split(),
        cwd=svc["WorkingDirectory"],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        yield proc, port
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        settings.write_text(original)


def test_the_units_command_serves_and_stops_in_order_on_sigterm(
    installed: Install, started: tuple[subprocess.Popen[bytes], int]
) -> None:
    proc, port = started
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60  # a cold numba cache compiles the kernel first
    with httpx.Client(base_url=base, timeout=5) as http:
        while True:
            assert proc.poll() is None, f"exited with {proc.returncode}"
            try:
                r = http.get("/api/health")
                break
            except httpx.TransportError:
                assert time.monotonic() < deadline, "no answer in 60 s"
                time.sleep(0.1)
        assert r.status_code == 200 and r.json() == {"status": "ok"}
        assert HMI_MARK in http.get("/").text  # INBETRIEB_FRONTEND_DIR: the installed HMI
    db = installed.path("/var/lib/inbetrieb/inbetrieb.sqlite")
    assert db.is_file()  # INBETRIEB_DB_PATH: the store where the unit says
    children = psutil.Process(proc.pid).children(recursive=True)
    assert children, "the worker process"
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)  # KillMode=mixed: the main process alone
    rc = proc.wait(10)
    # uvicorn re-raises the signal once it has stopped in order; systemd counts an end by
    # SIGTERM as clean (SuccessExitStatus), Docker as 143
    assert rc in (0, -signal.SIGTERM), rc
    assert time.monotonic() - t0 < 10
    _, alive = psutil.wait_procs(children, timeout=5)
    assert not alive, f"left running: {alive}"
    assert not Path(f"{db}-wal").exists(), "the store was closed"
