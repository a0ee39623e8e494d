"""A local multi-node Ray cluster for the Ray transport's tests and the cluster bench: a head
and worker nodes as separate raylets on this host, light enough for a 2-core machine.

Everything it makes stays in a new temp dir of its own, under the run's TMPDIR (under /tmp
when TMPDIR's path is too long for Ray's Unix sockets): Ray's session
files, sockets and logs, and the address file that `ray.cluster_utils.Cluster` writes to
`$RAY_TMPDIR/ray/ray_current_cluster` (`ray._common.utils.get_default_ray_temp_dir`; without
RAY_TMPDIR it would be `/tmp/ray`, which exists only where Ray ran before). Every node, the
GCS, the raylets and the Ray Client server listen on 127.0.0.1 only."""

from __future__ import annotations

import os

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # before ray loads: no usage reports
os.environ.setdefault("RAY_DEDUP_LOGS", "0")
# a test cluster idles most of its life: no metrics gathered and exported every few seconds by
# every node's agent, no idle worker processes started ahead (our actors get their own)
os.environ.setdefault("RAY_enable_metrics_collection", "0")
os.environ.setdefault("RAY_enable_worker_prestart", "0")
os.environ.setdefault("RAY_prestart_worker_first_driver", "0")
# Ray turns a loopback address given to ray.init into the host's outward address
# (`ray._private.services.resolve_ip_for_localhost`) unless this says the cluster is
# single-host (`ray_constants.ENABLE_RAY_CLUSTER`, read once when Ray loads)
os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"

import shutil
import socket
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from ray._private import ray_constants
from ray.cluster_utils import Cluster

if ray_constants.ENABLE_RAY_CLUSTER:
    raise RuntimeError("Ray was loaded before tests.backend.raycluster: it would leave loopback")

LOOPBACK = "127.0.0.1"
# one logical CPU each (the actors ask for none), the smallest object store Ray accepts + a
# bit; every listening socket on loopback (Ray binds its servers to the node's IP)
NODE_ARGS: dict[str, Any] = {
    "num_cpus": 1,
    "object_store_memory": 80 * 2**20,
    "node_ip_address": LOOPBACK,
}
# a node that stops answering is declared dead after ~1.5 s instead of Ray's default ~14 s
HEALTH = {
    "health_check_period_ms": 500,
    "health_check_timeout_ms": 500,
    "health_check_failure_threshold": 3,
}


def free_port() -> int:
    """A TCP port nothing listens on now (the OS picks it)."""
    with socket.socket() as s:
        s.bind((LOOPBACK, 0))
        port: int = s.getsockname()[1]
        return port


# Ray's longest Unix socket path below the cluster's temp dir (a socket path has at most 107
# bytes): /rayXXXXXXXX/ray/session_<date>_<time>_<µs>_<pid>/sockets/plasma_store
_SOCKET_TAIL = len(
    "/rayXXXXXXXX/ray/session_2026-11-27_20-14-13_123456_4194304/sockets/plasma_store"
)
_SOCKET_MAX = 107


def _temp_base() -> str:
    """The run's TMPDIR, or /tmp when TMPDIR's path is too long for Ray's sockets (a fresh
    folder of our own either way: nothing an earlier run left is used)."""
    base = tempfile.gettempdir()
    return base if len(base) + _SOCKET_TAIL <= _SOCKET_MAX else "/tmp"


class LocalCluster(Cluster):
    """A `Cluster` whose head also serves Ray Client."""

    client_address: str  # `ray://127.0.0.1:PORT`
    head_args: dict[str, Any]  # how the head was started (its ports among them)

    def restart_head(self) -> None:
        """Stop every node, the head last (as a head machine that reboots takes its cluster
        down), then start the head again on the same GCS and Ray Client ports and as many
        worker nodes as there were."""
        nodes = len(self.worker_nodes)
        for node in list(self.worker_nodes):
            self.remove_node(node)
        assert self.head_node is not None
        self.remove_node(self.head_node)
        # this process' view of the cluster: the new head is another cluster (Ray aborts
        # a process that asks the new head with the old cluster's id)
        self.global_state.disconnect()
        with warnings.catch_warnings():  # Ray drops its handles on the client server's logs
            warnings.simplefilter("ignore", ResourceWarning)
            self.add_node(**self.head_args)
        for _ in range(nodes):
            self.add_node(**NODE_ARGS)
        self.wait_for_nodes()


@contextmanager
def local_cluster(worker_nodes: int = 2) -> Iterator[LocalCluster]:
    """A head and `worker_nodes` nodes; shut down (every Ray process ended) afterwards.
    The head also serves Ray Client (`client_address`), as `ray start --head` does."""
    temp = tempfile.mkdtemp(prefix="ray", dir=_temp_base())
    ray_temp = os.path.join(temp, "ray")  # what Ray derives from RAY_TMPDIR for the address file
    os.makedirs(ray_temp)
    previous = os.environ.get("RAY_TMPDIR")
    os.environ["RAY_TMPDIR"] = temp  # inherited by every node and by the services started
    client_port = free_port()
    head = {
        **NODE_ARGS,
        "include_dashboard": False,
        "temp_dir": ray_temp,
        "_system_config": HEALTH,
        "ray_client_server_port": client_port,
    }
    cluster: LocalCluster | None = None
    try:
        with warnings.catch_warnings():  # Ray drops its handles on the client server's logs
            warnings.simplefilter("ignore", ResourceWarning)
            cluster = LocalCluster(initialize_head=True, head_node_args=head)
        cluster.client_address = f"ray://{LOOPBACK}:{client_port}"
        # the same GCS port when the head starts again (Ray chose it the first time)
        cluster.head_args = {**head, "gcs_server_port": int(cluster.address.rsplit(":", 1)[1])}
        for _ in range(worker_nodes):
            cluster.add_node(**NODE_ARGS)
        cluster.wait_for_nodes()
        yield cluster
    finally:
        if cluster is not None:
            cluster.shutdown()  # type: ignore[no-untyped-call]
        _restore(previous)
        shutil.rmtree(temp, ignore_errors=True)


def _restore(ray_tmpdir: str | None) -> None:
    if ray_tmpdir is None:
        os.environ.pop("RAY_TMPDIR", None)
    else:
        os.environ["RAY_TMPDIR"] = ray_tmpdir


def head_node_id(cluster: Cluster) -> str:
    """The head's node id, shortened as the service status shows it."""
    assert cluster.head_node is not None
    node_id: str = cluster.head_node.node_id
    return node_id[:8]
