"""A worker's side of training: faults into a machine's plant, snapshots of its state."""

from __future__ import annotations

from backend.workers.host import MachineHost
from backend.workers.protocol import Failure, InjectFault, RemoveFault, Snapshot, TakeSnapshot
from nc_sim.errors import NcUsageError
from nc_sim.sim import snapshot_bytes


def training_request(host: MachineHost, r: InjectFault | RemoveFault | TakeSnapshot) -> object:
    """Carry out one training request on the host's machine; the reply value."""
    m = host.machine
    match r:
        case InjectFault():
            try:
                fid = m.inject(r.fault, r.trigger)
            except (NcUsageError, ValueError) as e:
                return Failure("invalid", str(e))
            return next(f for f in m.faults() if f.id == fid)
        case RemoveFault():
            try:
                m.remove_fault(r.fid)
            except (NcUsageError, KeyError, ValueError) as e:
                return Failure("not_found", str(e))
            return None
        case TakeSnapshot():
            host.feed_monitor()
            return Snapshot(
                host.cycle, host.cycle * host.cycle_s, snapshot_bytes(host.sim), host.params_now()
            )
