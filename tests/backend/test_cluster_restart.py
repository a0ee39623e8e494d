"""A gateway on a Ray cluster (a Ray Client, as from outside the cluster) whose head
restarts: the actors and the connection are lost with it; the gateway joins the new head
when it is back (trying again, with growing waits, while it is not), starts its workers
there and rebuilds its machines from the store, their parameter values included."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.backend.raycluster import LocalCluster
from tests.backend.server import Server
from tests.backend.test_workers import service, wait_for

KV = "getriebe[0].kv"


@pytest.fixture
def gateway(
    ray_cluster: LocalCluster, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Server]:
    db = tmp_path_factory.mktemp("restart") / "r.sqlite"
    # the Ray Client waits 2 s for a lost head to answer again, not the service's 10 s (which
    # ride out a network blip): this head is gone for good, the test is about what follows
    grace = {"RAY_CLIENT_RECONNECT_GRACE_PERIOD": "2"}
    s = Server(db, "--cluster", ray_cluster.client_address, "--workers", "2", env=grace)
    yield s.start(timeout_s=180)
    s.close()


def _running_on(s: Server, nodes: set[str]) -> bool:
    """Every worker alive on one of `nodes`, and the demo machine powered on one of them."""
    workers = service(s)["workers"]
    live = [w for w in workers if w["alive"]]
    home = [w for w in live if "demo" in w["machines"]]
    if len(live) != 2 or not {w["node"] for w in live} <= nodes or len(home) != 1:
        return False
    r = s.http.get("/api/machines/demo/status")  # 503 while it is being rebuilt
    return r.status_code == 200 and r.json()["plc"]["drives_powered"] is True


def test_the_gateway_rejoins_a_head_that_restarted(
    gateway: Server, ray_cluster: LocalCluster
) -> None:
    s = gateway
    s.wait_powered("demo")
    body = {"changes": [{"scope": "axis", "target": "X", "name": KV, "value": 2600}]}
    assert s.http.patch("/api/machines/demo/parameters", json=body).status_code == 200
    before = {w["id"] for w in service(s)["workers"]}
    rebuilt = service(s)["machines_rebuilt"]

    ray_cluster.restart_head()
    nodes = {n.node_id[:8] for n in [ray_cluster.head_node, *ray_cluster.worker_nodes] if n}
    # lost (after the 2 s of Ray Client grace), joined again, two new actors that compile the
    # shipped kernel (≈10 s each on a busy 2-core machine): a safety net, not a measure
    wait_for(lambda: _running_on(s, nodes), 180)
    now = service(s)
    assert not before & {w["id"] for w in now["workers"] if w["alive"]}  # new workers
    assert now["machines_rebuilt"] >= rebuilt + 1
    x = s.http.get("/api/machines/demo/parameters", params={"scope": "axis", "target": "X"})
    assert {p["name"]: p["value"] for p in x.json()}[KV] == 2600  # from the store
    r = s.command("demo", {"type": "mdi", "block": "M3 S500"})
    assert r.status_code == 200 and r.json()["accepted"], r.text
