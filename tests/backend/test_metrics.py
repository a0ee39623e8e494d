"""`/metrics` over real HTTP, read with prometheus_client's own parser: the figures agree with
the service status, a command's latency lands in its histogram (never longer than the round
trip the client measured), and nobody reads them without a login."""

from __future__ import annotations

import time

import httpx
from prometheus_client.parser import text_string_to_metric_families

from tests.backend.server import Server


def _scrape(srv: Server) -> dict[str, dict[tuple[tuple[str, str], ...], float]]:
    """name -> {labels: value} of every sample."""
    r = srv.http.get("/metrics")
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("text/plain")
    out: dict[str, dict[tuple[tuple[str, str], ...], float]] = {}
    for family in text_string_to_metric_families(r.text):
        for s in family.samples:
            out.setdefault(s.name, {})[tuple(sorted(s.labels.items()))] = s.value
    return out


def _mdi_count(m: dict[str, dict[tuple[tuple[str, str], ...], float]]) -> float:
    return m.get("inbetrieb_command_latency_seconds_count", {}).get((("type", "mdi"),), 0.0)


def test_metrics_agree_with_the_status_and_time_commands(srv: Server, mid: str) -> None:
    before = _scrape(srv)
    t0 = time.perf_counter()
    r = srv.command(mid, {"type": "mdi", "block": "G90"})
    round_trip_s = time.perf_counter() - t0
    assert r.status_code == 200, r.text
    m = _scrape(srv)
    status = srv.http.get("/api/service/status").json()

    assert _mdi_count(m) == _mdi_count(before) + 1
    buckets = {
        float(dict(k)["le"]): v
        for k, v in m["inbetrieb_command_latency_seconds_bucket"].items()
        if dict(k)["type"] == "mdi"
    }
    counts = [buckets[le] for le in sorted(buckets)]
    assert counts == sorted(counts) and counts[-1] == _mdi_count(m)  # cumulative, +Inf last
    took = m["inbetrieb_command_latency_seconds_sum"][(("type", "mdi"),)] - before.get(
        "inbetrieb_command_latency_seconds_sum", {}
    ).get((("type", "mdi"),), 0.0)
    assert 0.0 < took <= round_trip_s

    modes = {dict(k)["mode"]: v for k, v in m["inbetrieb_machines"].items()}
    assert sum(modes.values()) == len(status["machines"])
    assert modes["run"] == sum(1 for s in status["machines"].values() if s["mode"] == "run")
    for w in status["workers"]:
        key = (("node", w["node"]), ("worker", w["id"]))
        assert m["inbetrieb_worker_up"][key] == (1.0 if w["alive"] else 0.0)
        assert m["inbetrieb_worker_machines"][key] == len(w["machines"])
        assert m["inbetrieb_worker_pending_calls"][key] >= 0
    assert m["inbetrieb_telemetry_clients"][()] == status["clients"]
    assert m["inbetrieb_info"][(("transport", "local"), ("version", status["version"]))] == 1.0

    anonymous = httpx.get(f"{srv.base}/metrics")
    assert anonymous.status_code == 401
