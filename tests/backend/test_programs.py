"""Stored NC programs over real HTTP (list, read, write, delete, audited with the actor),
their limits (oversized and malformed bodies are 4xx, nothing stored), the preview of a
program on a machine, and `program_load` of a stored program by name."""

from __future__ import annotations

import math
import sqlite3
import time
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path
from typing import Any

import pytest

from api.auth import Role
from api.commands import PROGRAM_MAX_CHARS
from backend.services.store import Store
from nc_sim.errors import Code
from tests.backend.server import USER, Server, add_users, bearer

LATHE = "G18 G90\nG00 X40 Z5\nG01 Z-20 F300\nG02 X45 Z-25 K0 I5\nG00 X80\nM30\n"


TOKENS: dict[str, str] = {}  # the module's observer and operator


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    db: Path = tmp_path_factory.mktemp("programs") / "db.sqlite"
    TOKENS.update(add_users(db, {"olga": Role.OBSERVER, "otto": Role.OPERATOR}))
    s = Server(db, "--no-demo").start()
    yield s
    s.close()


def _audit(s: Server, **params: Any) -> list[dict[str, Any]]:
    r = s.http.get("/api/audit", params={"kind": "program", **params})
    assert r.status_code == 200, r.text
    rows: list[dict[str, Any]] = r.json()["rows"]
    return rows


def test_write_list_read_replace_delete(srv: Server) -> None:
    otto = bearer(TOKENS["otto"])
    before = time.time()
    r = srv.http.put("/api/programs/turn_1.nc", json={"text": LATHE}, headers=otto)
    assert r.status_code == 200, r.text
    info = r.json()
    assert info["name"] == "turn_1.nc" and info["updated_by"] == "otto"
    assert info["size"] == len(LATHE) and info["lines"] == 6
    when = datetime.fromisoformat(info["updated_at"])
    assert when.utcoffset() is not None and when.utcoffset().total_seconds() == 0  # type: ignore[union-attr]
    assert before - 1 <= when.timestamp() <= time.time() + 1

    listed = {p["name"]: p for p in srv.http.get("/api/programs").json()}
    assert listed["turn_1.nc"] == info and "text" not in listed["turn_1.nc"]
    got = srv.http.get("/api/programs/TURN_1.NC").json()  # names match regardless of case
    assert got["text"] == LATHE and got["name"] == "turn_1.nc"

    r = srv.http.put("/api/programs/turn_1.nc", json={"text": "M30"})  # the admin replaces it
    assert r.status_code == 200 and r.json()["updated_by"] == USER and r.json()["lines"] == 1
    assert srv.http.get("/api/programs/turn_1.nc").json()["text"] == "M30"

    assert srv.http.delete("/api/programs/turn_1.nc", headers=otto).status_code == 204
    assert srv.http.get("/api/programs/turn_1.nc").status_code == 404
    assert srv.http.delete("/api/programs/turn_1.nc").status_code == 404
    assert "turn_1.nc" not in {p["name"] for p in srv.http.get("/api/programs").json()}

    actions = [(row["actor"], row["action"]) for row in reversed(_audit(srv))]
    assert ("otto", f"created program turn_1.nc ({len(LATHE)} characters)") in actions
    assert (USER, "replaced program turn_1.nc (3 characters)") in actions
    assert ("otto", "deleted program turn_1.nc") in actions


def test_an_observer_reads_but_may_not_write(srv: Server) -> None:
    olga = bearer(TOKENS["olga"])
    srv.http.put("/api/programs/shared", json={"text": "M30"}).raise_for_status()
    assert srv.http.get("/api/programs/shared", headers=olga).status_code == 200
    r = srv.http.put("/api/programs/shared", json={"text": "G00 X1\nM30"}, headers=olga)
    assert r.status_code == 403
    assert srv.http.delete("/api/programs/shared", headers=olga).status_code == 403
    assert srv.http.get("/api/programs/shared").json()["text"] == "M30"
    refused = _audit(srv, user="olga")
    assert refused and refused[0]["outcome"].startswith("refused (403)")


def test_oversized_and_malformed_bodies_are_refused_and_store_nothing(srv: Server) -> None:
    too_long = {"text": "G" * (PROGRAM_MAX_CHARS + 1)}
    r = srv.http.put("/api/programs/big", json=too_long)
    assert r.status_code == 422, r.text
    assert "2000000" in r.text.replace("_", "").replace(",", "")
    huge = b'{"text": "' + b"\\u00e4" * (PROGRAM_MAX_CHARS + 1000) + b'"}'  # > 8 MB of JSON
    r = srv.http.put(
        "/api/programs/big", content=huge, headers={"content-type": "application/json"}
    )
    assert r.status_code == 413, r.text
    for body in (b"{not json", b'{"text": 5}', b"[]", "ä".encode("latin-1")):
        r = srv.http.put(
            "/api/programs/big", content=body, headers={"content-type": "application/json"}
        )
        assert r.status_code == 422, (body, r.text)
    assert srv.http.put("/api/programs/.hidden", json={"text": "M30"}).status_code == 422
    slash = srv.http.put("/api/programs/a%2Fb", json={"text": "M30"})  # no route takes a/b
    assert 400 <= slash.status_code < 500
    assert "big" not in {p["name"] for p in srv.http.get("/api/programs").json()}


def _preview(srv: Server, mid: str, text: str) -> dict[str, Any]:
    r = srv.http.post(f"/api/machines/{mid}/program-preview", json={"text": text})
    assert r.status_code == 200, r.text
    body: dict[str, Any] = r.json()
    return body


def test_preview_draws_the_lathe_path_in_zx_from_where_the_axes_are(
    srv: Server, lathe: str
) -> None:
    at = {a["name"]: a["pos_cmd"] for a in srv.status(lathe)["axes"]}
    p = _preview(srv, lathe, LATHE)
    assert p["error"] is None and p["plane"] == "G18" and p["axes"] == ["Z", "X"]
    rapid, feed, arc, away = p["segments"]
    assert rapid == {"line": 2, "rapid": True, "points": [[at["Z"], at["X"]], [5.0, 40.0]]}
    assert feed == {"line": 3, "rapid": False, "points": [[5.0, 40.0], [-20.0, 40.0]]}
    # G02 from (Z-20, X40) to (Z-25, X45) about (Z-20, X45) (K0 I5), radius 5: clockwise
    # with Z across and X up, a quarter through the lower left (Z < -20, X < 45)
    assert arc["line"] == 4 and arc["points"][0] == [-20.0, 40.0]
    assert arc["points"][-1] == [-25.0, 45.0]
    assert all(z <= -20.0 + 1e-9 and x <= 45.0 + 1e-9 for z, x in arc["points"])
    for z, x in arc["points"]:
        assert abs(math.hypot(z + 20.0, x - 45.0) - 5.0) <= 1e-6
    assert away["rapid"] and away["points"][-1] == [-25.0, 80.0]


def test_preview_marks_the_first_error_and_draws_what_came_before(srv: Server, lathe: str) -> None:
    text = "G18\nG00 X40 Z5\nG01 Z-20 F300\nG01 X45 Q7\nG00 X80\nM30\n"
    p = _preview(srv, lathe, text)
    err = p["error"]
    assert (err["line"], err["column"], err["code"]) == (4, 9, int(Code.BLOCK_SYNTAX))
    assert "Q" in err["message"]
    assert [s["line"] for s in p["segments"]] == [2, 3]


def test_preview_refuses_oversized_text_and_unknown_machines(srv: Server, lathe: str) -> None:
    r = srv.http.post(
        f"/api/machines/{lathe}/program-preview", json={"text": "M30\n" * PROGRAM_MAX_CHARS}
    )
    assert r.status_code in (413, 422)
    r = srv.http.post("/api/machines/nope/program-preview", json={"text": "M30"})
    assert r.status_code == 404


def test_program_load_by_name_loads_the_stored_program(srv: Server, lathe: str) -> None:
    srv.http.put("/api/programs/stored_turn", json={"text": LATHE}).raise_for_status()
    r = srv.command(lathe, {"type": "program_load", "name": "stored_turn"})
    assert r.status_code == 200, r.text
    channel = srv.status(lathe)["channel"]
    assert channel["program"] == "stored_turn"

    r = srv.command(lathe, {"type": "program_load", "name": "no_such_program"})
    assert r.status_code == 404, r.text
    assert "no_such_program" in r.json()["detail"]["message"]

    srv.http.put("/api/programs/bad_turn", json={"text": "G00 X1\nG01 Z2\nM30"})
    r = srv.command(lathe, {"type": "program_load", "name": "bad_turn"})
    assert r.status_code == 422, r.text
    assert (r.json()["detail"]["line"], r.json()["detail"]["code"]) == (2, int(Code.FEED_MISSING))


def test_preview_of_a_c_axis_program_draws_x_and_z(srv: Server, lathe: str) -> None:
    """003 §1.2's switching example on the demo lathe (S1 is C): C words, #CAX and M3 change
    the mode and are no errors; the drawing in ZX follows X and Z, C turns in place."""
    text = (
        "G18\nM19 S.POS=0\nG00 X100 Z200 M3 S1000\nG00 X100 Z250 C90\n"
        "G01 G91 X40 C-270 F1200\n#CAX OFF\nG90 G00 X120 Z200 M3 S1200\nM30\n"
    )
    p = _preview(srv, lathe, text)
    assert p["error"] is None, p["error"]
    ends = {s["line"]: s["points"][-1] for s in p["segments"]}
    assert ends[3] == [200.0, 100.0] and ends[4] == [250.0, 100.0]
    assert ends[5] == [250.0, 140.0] and ends[7] == [200.0, 120.0]


def test_a_store_of_an_earlier_version_keeps_its_programs_service_wide(tmp_path: Path) -> None:
    """Programs were keyed by name alone; opened now, each is a service-wide one."""
    db = tmp_path / "old.sqlite"
    with sqlite3.connect(db) as old:
        old.execute(
            "CREATE TABLE programs (name TEXT PRIMARY KEY, text TEXT NOT NULL, size INTEGER "
            "NOT NULL, lines INTEGER NOT NULL, updated REAL NOT NULL, updated_by TEXT NOT NULL)"
        )
        old.execute("INSERT INTO programs VALUES ('Part1', 'M30\n', 4, 1, 1.0e9, 'ann')")
    store = Store(db)
    try:
        (p,) = store.programs(("",))
        assert (p.name, p.owner, p.updated_by) == ("Part1", "", "ann")
        found = store.program("PART1", ("seat-s01", ""))
        assert found is not None and found.text == "M30\n"
    finally:
        store.close()
