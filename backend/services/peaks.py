"""Each axis' lag and speed of the largest magnitude (sign kept) in every cycle since the last
look, from the sample ring a machine's worker writes: what a display or a recording that
looks now and then must not miss in between (a status is one cycle out of a hundred)."""

from __future__ import annotations

from backend.services.machines import MachineProxy
from nc_sim.signals import Signal

# an axis' lag and speed signals (nc_sim/signals.py), by the axis' kind
LAG_SIGNALS = ("lag_mm", "lag_deg")
SPEED_SIGNALS = ("speed_act_rpm", "vel_act_mm_min", "vel_act_deg_min")

Peaks = dict[str, tuple[float, float]]  # axis -> (lag, speed) of the largest magnitude


def _signal(m: MachineProxy, axis: str, names: tuple[str, ...]) -> Signal | None:
    """The axis' first signal of these names that the machine records."""
    return next(
        (s for n in names if (s := m.link.signal_by_name.get(f"{axis}.{n}")) is not None), None
    )


class PeakReader:
    """Reads machines' peaks, each from where its last read ended."""

    def __init__(self, first_look_s: float) -> None:
        self.first_look_s = first_look_s  # how far back a machine's first read goes
        self._from: dict[str, tuple[int, int]] = {}  # machine -> (epoch, next cycle)

    def peaks(self, m: MachineProxy) -> Peaks:
        """Each axis' peaks in the cycles since the last read (as far back as the ring holds
        them: a machine run fast in between; `first_look_s` back for a first read or a new
        build; the newest cycle's while it stands paused)."""
        ring, epoch = m.link.ring, m.link.epoch
        if ring is None:
            return {}
        head = ring.head
        known, first = self._from.get(m.id, (-1, 0))
        if known != epoch:
            first = head - round(self.first_look_s / m.link.cycle_s) + 1
        first = min(max(first, 1), head)
        lines = [
            (a, lag, speed)
            for a in m.link.axes
            if (lag := _signal(m, a, LAG_SIGNALS)) and (speed := _signal(m, a, SPEED_SIGNALS))
        ]
        if first < 1 or not lines:
            return {}
        try:
            peak = ring.peaks([s for _a, lag, speed in lines for s in (lag, speed)], first, head)
        except IndexError:  # the machine was rebuilt meanwhile: its old ring is closed
            return {}
        self._from[m.id] = (epoch, head + 1)
        if peak is None:
            return {}
        return {
            a: (float(peak[2 * i]), float(peak[2 * i + 1])) for i, (a, _l, _s) in enumerate(lines)
        }
