"""A store made by the release before the schema versions (main at e6f198c: its SQL dump
and trace file under fixtures/) opens in `inbetrieb serve`, is upgraded step by step, and
keeps its users, parameter values, versions, programs, traces and audit trail. A store of a
newer release is refused, by the service and by a restore, and left as it was.

How the fixture was made (at e6f198c): a service on a fresh store; `inbetrieb user add ute
--role operator` with the password "correct horse"; X's getriebe[0].kv written 2500 then 3000;
a CSV trace imported (t_s 0, 0.001, 0.002 → X.lag_mm 1.0, 2.5, 4.0); the program FIXTURE.NC;
a version "after kv tuning X" taken as the baseline; the service stopped; `.dump` of the file.
"""

from __future__ import annotations

import json
import shutil
import sqlite3
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from backend import VERSION
from backend.services.store import STEPS, Store
from tests.backend.server import PASSWORD, ROOT, USER, Server, bearer

FIXTURE = Path(__file__).parent / "fixtures" / "store-e6f198c"
KV = "getriebe[0].kv"


def old_store(folder: Path) -> Path:
    """The fixture as the old release left it: its SQLite file and its traces beside it."""
    db = folder / "store.sqlite"
    con = sqlite3.connect(db)
    con.executescript((FIXTURE / "store.sql").read_text())
    con.close()
    shutil.copytree(FIXTURE / "traces", folder / "traces")
    return db


@pytest.fixture(scope="module")
def upgraded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Server, Path]]:
    folder = tmp_path_factory.mktemp("upgrade")
    db = old_store(folder)
    log = folder / "log.jsonl"
    env = {"INBETRIEB_LOG_FORMAT": "json", "INBETRIEB_LOG_LEVEL": "info"}
    s = Server(db, env=env, seed=False)
    with log.open("w") as out:
        s.start(stdout=out)
    # the old admin's password still logs in; scripts use a token (made after the upgrade)
    assert s.http.post("/api/auth/login", json={"name": USER, "password": PASSWORD}).is_success
    cmd = [sys.executable, "-m", "backend.cli", "token", "create", "--user", USER, "--db", str(db)]
    token = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True).stdout
    s.http.cookies.clear()
    s.http.headers.update(bearer(token.strip()))
    yield s, log
    s.close()


def test_the_old_store_keeps_its_users_values_versions_programs_and_traces(
    upgraded: tuple[Server, Path],
) -> None:
    s, _ = upgraded
    with httpx.Client(base_url=s.base, timeout=10) as ute:
        r = ute.post("/api/auth/login", json={"name": "ute", "password": "correct horse"})
        assert r.status_code == 200, r.text  # the argon2 hash of the old release still checks
        assert ute.get("/api/auth/me").json()["role"] == "operator"
    x = s.http.get("/api/machines/demo/parameters", params={"scope": "axis", "target": "X"})
    assert {p["name"]: p["value"] for p in x.json()}[KV] == 3000
    versions = s.http.get("/api/machines/demo/versions").json()
    assert [(v["name"], v["baseline"]) for v in versions] == [("after kv tuning X", True)]
    program = s.http.get("/api/programs/FIXTURE.NC").json()
    assert program["text"] == "N10 G01 X10 F1000\nN20 M30\n"
    (trace,) = s.http.get("/api/traces").json()
    csv = s.http.get(f"/api/traces/{trace['id']}/csv").text
    lag = [float(line.split(",")[-1]) for line in csv.splitlines()[-3:]]
    assert lag == [1.0, 2.5, 4.0]
    # the old rows are still one unbroken chain (the new column is no part of the hash)
    assert s.http.get("/api/audit/verify").json()["ok"] is True
    kv_rows = s.http.get("/api/audit", params={"text": KV}).json()["rows"]
    assert len(kv_rows) >= 2 and {r["request_id"] for r in kv_rows} == {""}


def test_the_store_records_each_step_of_the_upgrade(upgraded: tuple[Server, Path]) -> None:
    s, _ = upgraded
    con = sqlite3.connect(f"file:{s.db}?mode=ro", uri=True)
    try:
        taken = con.execute("SELECT version, release FROM schema_version ORDER BY version")
        assert taken.fetchall() == [(step.version, VERSION) for step in STEPS]
        columns = {c[1] for c in con.execute("PRAGMA table_info(audit_log)")}
    finally:
        con.close()
    assert "request_id" in columns


def test_a_write_names_its_request_in_the_audit_row_and_the_json_log(
    upgraded: tuple[Server, Path],
) -> None:
    s, log = upgraded
    body = {"changes": [{"scope": "axis", "target": "X", "name": KV, "value": 3100}]}
    r = s.http.patch(
        "/api/machines/demo/parameters", json=body, headers={"X-Request-ID": "ticket-4711"}
    )
    assert r.status_code == 200, r.text
    assert r.headers["x-request-id"] == "ticket-4711"
    newest = s.http.get("/api/audit", params={"text": KV, "limit": 1}).json()["rows"][0]
    assert newest["request_id"] == "ticket-4711"
    unsafe = s.http.get("/api/health", headers={"X-Request-ID": "<script>" + "x" * 100})
    assert len(unsafe.headers["x-request-id"]) == 16  # not kept: a new one instead
    s.http.get("/api/auth/me")  # a line after the write's: it has been flushed
    lines = [json.loads(line) for line in log.read_text().splitlines() if line.startswith("{")]
    (access,) = [entry for entry in lines if entry["request_id"] == "ticket-4711"]
    assert access["logger"] == "inbetrieb.access"
    assert (access["method"], access["path"], access["status"]) == (
        "PATCH",
        "/api/machines/demo/parameters",
        200,
    )
    assert access["actor"] == USER and access["duration_ms"] >= 0


def test_a_store_of_a_newer_release_is_refused_and_left_as_it_is(tmp_path: Path) -> None:
    db = old_store(tmp_path)
    con = sqlite3.connect(db)
    con.execute("CREATE TABLE schema_version (version INTEGER PRIMARY KEY, what, release, time)")
    con.execute("INSERT INTO schema_version VALUES (99, 'from the future', '9.0', 0)")
    con.commit()
    con.close()
    before = db.read_bytes()
    cmd = [sys.executable, "-m", "backend.cli", "serve", "--port", "1", "--db", str(db)]
    out = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode == 2, out.stderr
    assert "schema version 99" in out.stderr and "newer release" in out.stderr
    assert db.read_bytes() == before
    # nor does a backup of it restore over a store of this release
    archive = tmp_path / "future.tar.gz"
    cli = [sys.executable, "-m", "backend.cli"]
    made = subprocess.run([*cli, "backup", str(archive), "--db", str(db)], cwd=ROOT, timeout=60)
    assert made.returncode == 0
    target = tmp_path / "here" / "store.sqlite"
    back = subprocess.run(
        [*cli, "restore", str(archive), "--db", str(target)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert back.returncode == 2 and "newer release" in back.stderr, back.stderr
    assert not target.exists()


def test_a_new_store_starts_at_the_newest_version_and_closes_into_one_file(
    tmp_path: Path,
) -> None:
    db = tmp_path / "new.sqlite"
    store = Store(db)
    assert store.steps_taken == []  # made by today's CREATE statements: nothing to upgrade
    store.run("INSERT INTO machines VALUES ('m', 'M', 'demo', '', '{}', '', 0)")
    store.close()
    wal = db.with_name(db.name + "-wal")
    assert not wal.exists() or wal.stat().st_size == 0  # folded into the file at close
    con = sqlite3.connect(db)
    try:
        versions = [v for (v,) in con.execute("SELECT version FROM schema_version")]
    finally:
        con.close()
    assert versions == [step.version for step in STEPS]
    assert [step.version for step in STEPS] == list(range(1, len(STEPS) + 1))
