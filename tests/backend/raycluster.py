"""A local multi-node Ray cluster for the Ray transport's tests and the cluster bench: a head
and worker nodes as separate raylets on this host, light enough for a 2-core machine."""

from __future__ import annotations

import os

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # before ray loads: no usage reports
os.environ.setdefault("RAY_DEDUP_LOGS", "0")

import shutil
import socket
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ray.cluster_utils import Cluster

# one logical CPU each (the actors ask for none), the smallest object store Ray accepts + a bit
NODE_ARGS: dict[str, Any] = {"num_cpus": 1, "object_store_memory": 80 * 2**20}
# a node that stops answering is declared dead after ~1.5 s instead of Ray's default ~14 s
HEALTH = {
    "health_check_period_ms": 500,
    "health_check_timeout_ms": 500,
    "health_check_failure_threshold": 3,
}


def free_port() -> int:
    """A TCP port nothing listens on now (the OS picks it)."""
    with socket.socket() as s:
        s.bind(("", 0))
        port: int = s.getsockname()[1]
        return port


class LocalCluster(Cluster):
    """A `Cluster` whose head also serves Ray Client."""

    client_address: str  # `ray://HOST:PORT`; the server listens on the node's IP only


@contextmanager
def local_cluster(worker_nodes: int = 2) -> Iterator[LocalCluster]:
    """A head and `worker_nodes` nodes; shut down (every Ray process ended) afterwards.
    The head also serves Ray Client (`client_address`), as `ray start --head` does."""
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Unix socket paths ≤ 107 chars
    client_port = free_port()
    head = {
        **NODE_ARGS,
        "include_dashboard": False,
        "temp_dir": temp,
        "_system_config": HEALTH,
        "ray_client_server_port": client_port,
    }
    with warnings.catch_warnings():  # Ray drops its handles on the client server's log files
        warnings.simplefilter("ignore", ResourceWarning)
        cluster = LocalCluster(initialize_head=True, head_node_args=head)
    host = cluster.address.rsplit(":", 1)[0]
    cluster.client_address = f"ray://{host}:{client_port}"
    try:
        for _ in range(worker_nodes):
            cluster.add_node(**NODE_ARGS)
        cluster.wait_for_nodes()
        yield cluster
    finally:
        cluster.shutdown()  # type: ignore[no-untyped-call]
        shutil.rmtree(temp, ignore_errors=True)


def head_node_id(cluster: Cluster) -> str:
    """The head's node id, shortened as the service status shows it."""
    assert cluster.head_node is not None
    node_id: str = cluster.head_node.node_id
    return node_id[:8]
