"""Integers beyond what the store holds (SQLite's signed 64 bits) are refused by the API as out
of range, naming the value, instead of overflowing in the store (an OverflowError was a 500)."""

from __future__ import annotations

from typing import Any

import pytest

from tests.backend.server import Server

JUST_OVER = 2**63  # one more than SQLite's largest integer


@pytest.mark.parametrize(
    ("method", "path", "body", "loc"),
    [
        ("GET", "/api/machines/{mid}/audit?before_seq={n}", None, ["query", "before_seq"]),
        ("GET", "/api/audit?before_seq={n}", None, ["query", "before_seq"]),
        ("GET", "/api/machines/{mid}/assist/runs/{n}", None, ["path", "run_id"]),
        (
            "POST",
            "/api/machines/{mid}/simulation",
            {"mode": "fast", "until_cycle": "{n}"},
            ["body", "until_cycle"],
        ),
        (
            "PATCH",
            "/api/machines/{mid}/parameters",
            {
                "changes": [
                    {
                        "scope": "axis",
                        "target": "X",
                        "name": "getriebe[0].kv",
                        "value": 1,
                        "base_version": "{n}",
                    }
                ]
            },
            ["body", "changes", 0, "base_version"],
        ),
    ],
)
def test_a_number_past_64_bits_is_refused_with_its_name(
    srv: Server, mid: str, method: str, path: str, body: dict[str, Any] | None, loc: list[Any]
) -> None:
    def filled(value: Any) -> Any:
        if value == "{n}":
            return JUST_OVER
        if isinstance(value, dict):
            return {k: filled(v) for k, v in value.items()}
        if isinstance(value, list):
            return [filled(v) for v in value]
        return value

    r = srv.http.request(method, path.format(mid=mid, n=JUST_OVER), json=filled(body))
    assert r.status_code == 422, r.text
    (issue,) = r.json()["detail"]
    assert issue["loc"] == loc and issue["type"] == "less_than_equal"
    assert str(2**63 - 1) in issue["msg"]
