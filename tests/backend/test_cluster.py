"""A real gateway on a local multi-node Ray cluster, joined both ways: as a driver on the head
node (`inbetrieb serve --cluster HOST:PORT`) and as a Ray Client (`--cluster ray://HOST:PORT`,
the gateway's code shipped with the job). Its workers are actors spread over the nodes,
machines on them answer commands and stream telemetry, and a node that leaves the cluster has
its machines rebuilt on the others."""

from __future__ import annotations

import asyncio
import ipaddress
import itertools
from collections.abc import Iterator

import psutil
import pytest

from api.telemetry import FrameHeader
from tests.backend.raycluster import NODE_ARGS, LocalCluster, head_node_id
from tests.backend.server import Server
from tests.backend.test_workers import service, wait_for, watch, worker_of


@pytest.fixture(scope="module", params=["gcs", "client"])
def srv(
    request: pytest.FixtureRequest,
    ray_cluster: LocalCluster,
    tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[Server]:
    """A gateway with 3 workers, on the head node (GCS address) or a Ray Client."""
    address = ray_cluster.address if request.param == "gcs" else ray_cluster.client_address
    db = tmp_path_factory.mktemp("cluster") / "c.sqlite"
    # a Ray Client gateway ships its code and starts a server per client: on a busy 2-core
    # machine that takes longer than a local service
    s = Server(db, "--cluster", address, "--workers", "3").start(timeout_s=180)
    yield s
    s.close()


def machines_on_every_node(srv: Server) -> list[str]:
    """One new machine per worker (placed by load: each joins the emptiest worker)."""
    ids = []
    for k in range(len(service(srv)["workers"])):
        name = f"n{k}"
        r = srv.http.post("/api/machines", json={"id": name, "demo": True})
        assert r.status_code == 201, r.text
        ids.append(name)
    for name in ids:
        srv.wait_powered(name)
    return ids


def frames_of(srv: Server, mid: str, seconds: float) -> list[FrameHeader]:
    async def run() -> list[FrameHeader]:
        stop = asyncio.Event()
        task = asyncio.create_task(watch(srv, mid, stop))
        await asyncio.sleep(seconds)
        stop.set()
        return (await task)[0]

    return asyncio.run(run())


def test_machines_run_on_every_node_and_answer_and_stream(
    srv: Server, ray_cluster: LocalCluster
) -> None:
    workers = service(srv)["workers"]
    nodes = {head_node_id(ray_cluster), *(n.node_id[:8] for n in ray_cluster.worker_nodes)}
    assert len(workers) == 3 and {w["node"] for w in workers} == nodes  # one per node
    assert service(srv)["transport"] == "ray"
    ids = machines_on_every_node(srv)
    assert {worker_of(srv, m)["node"] for m in ids} == nodes
    for mid in ids:
        r = srv.command(mid, {"type": "mdi", "block": "M3 S1000"})
        assert r.status_code == 200 and r.json()["accepted"], r.text
        r = srv.command(mid, {"type": "mdi", "block": "G01 X10 F500 &"})
        assert r.status_code == 422, r.text
    # telemetry from a machine on a worker node: every cycle, in order, nothing skipped
    remote = next(m for m in ids if worker_of(srv, m)["node"] != head_node_id(ray_cluster))
    frames = frames_of(srv, remote, 1.5)
    assert len(frames) > 5  # batches of the worker's polls: a frame per poll or two
    for prev, h in itertools.pairwise(frames):
        assert h.first_cycle == prev.first_cycle + prev.count * prev.stride
        assert h.skipped_cycles == 0
    # and the spindle reaches the commanded 1000 rpm
    wait_for(lambda: srv.axis("S1", remote)["vel_cmd"] == pytest.approx(1000.0))


def test_a_node_that_leaves_has_its_machines_rebuilt_on_the_others(
    srv: Server, ray_cluster: LocalCluster
) -> None:
    head = head_node_id(ray_cluster)  # the gateway's own node: it stays
    for k in itertools.count():  # placed by load: within a round one lands on a worker node
        leaver = f"leaver{k}"
        r = srv.http.post("/api/machines", json={"id": leaver, "demo": True})
        assert r.status_code == 201, r.text
        home = worker_of(srv, leaver)
        if home["node"] != head:
            break
        assert k < 3, "no machine was placed on a worker node"
    srv.wait_powered(leaver)
    node = next(n for n in ray_cluster.worker_nodes if n.node_id[:8] == home["node"])
    before = service(srv)["machines_rebuilt"]
    ray_cluster.remove_node(node)
    try:
        lost = len(home["machines"])  # every machine of the node's worker, rebuilt elsewhere
        wait_for(lambda: service(srv)["machines_rebuilt"] == before + lost, 30)
        new_home = worker_of(srv, leaver)
        assert new_home["node"] != home["node"] and new_home["id"] != home["id"]
        srv.wait_powered(leaver)  # the machine answers again, rebuilt and powered on
        r = srv.command(leaver, {"type": "mdi", "block": "M3 S500"})
        assert r.status_code == 200 and r.json()["accepted"], r.text
        # the node's worker is dead: listed as such, or replaced already
        assert not any(w["alive"] for w in service(srv)["workers"] if w["id"] == home["id"])
    finally:
        ray_cluster.add_node(**NODE_ARGS)  # the next tests find the cluster as it was
        ray_cluster.wait_for_nodes()


def test_the_cluster_and_the_gateway_listen_on_loopback_only(
    srv: Server, ray_cluster: LocalCluster
) -> None:
    """Every socket that the nodes (GCS, raylets, agents, the Ray Client server), the gateway
    and its actors listen on is bound to a loopback address: a test reaches no network."""
    listening: dict[tuple[str, int], str] = {}
    for proc in psutil.Process().children(recursive=True):
        try:
            sockets = proc.net_connections(kind="inet")
            name = proc.name()
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        for s in sockets:
            if s.status == psutil.CONN_LISTEN:
                listening[(s.laddr.ip, s.laddr.port)] = name
    ports = {port for _, port in listening}
    gcs_port = int(ray_cluster.address.rsplit(":", 1)[1])
    client_port = int(ray_cluster.client_address.rsplit(":", 1)[1])
    assert {srv.port, gcs_port, client_port} <= ports, listening  # the ones we know are seen
    outward = {
        f"{ip}:{port} ({name})"
        for (ip, port), name in listening.items()
        if not ipaddress.ip_address(ip.removeprefix("::ffff:")).is_loopback
    }
    assert not outward
