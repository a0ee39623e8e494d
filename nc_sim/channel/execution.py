"""Program execution: canonical calls -> path elements and channel actions, in time.

`Execution` walks the calls of an interpreted program. Motion calls become path elements,
queued for the look-ahead (`Path`); everything else is an action the channel does between
them. When an action acts and what the path waits for is the synchronisation type's business
[000 §2.5]:

- MVS_SVS: the path comes to rest, the action starts, the path waits until it is done, then
  the block's motion follows. M3/M4/M5 always synchronise internally on speed reached or
  standstill [000 §2.5.1], so NO_SYNCH means this for them (and for M19: in position);
- MOS (and NO_SYNCH for S alone, s_synch P-CHAN-00081): the action starts when the path gets
  there, the path does not wait;
- MVS_SNS: starts when the path gets there, the path waits after the block's motion;
- MNS_SNS (and MNE_SNS, no measuring events here): starts after the block's motion, waits;
- MVS_SLM: starts when the path gets there, the path waits before the next G01/G02/G03;
- MVS_SLP: starts when the path gets there, waits at the program end (no #EXPL SYN here);
- PLC_INFO (additive): the M function also goes to the PLC, and its acknowledgement is waited
  for with the same timing.
Priority within a block M19 > M3/M4/M5 > S: only the highest spindle function of a block
synchronises (the interpreter emits at most one per spindle and block).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from nc_sim.channel import canon
from nc_sim.channel.coupling import Coupling
from nc_sim.channel.geometry import Element, arc, straight
from nc_sim.kernel import layout as L
from nc_sim.params.definitions import SYNC_SYMBOLS

# synchronisation types [000 §2.5], as the parameter lists spell them
MOS = SYNC_SYMBOLS["MOS"]
MVS_SVS = SYNC_SYMBOLS["MVS_SVS"]
MVS_SNS = SYNC_SYMBOLS["MVS_SNS"]
MNS_SNS = SYNC_SYMBOLS["MNS_SNS"]
MNE_SNS = SYNC_SYMBOLS["MNE_SNS"]
MVS_SLM = SYNC_SYMBOLS["MVS_SLM"]
MVS_SLP = SYNC_SYMBOLS["MVS_SLP"]
PLC_INFO = SYNC_SYMBOLS["PLC_INFO"]

_MOTION = (
    canon.StraightTraverse,
    canon.StraightFeed,
    canon.ArcFeed,
    canon.ThreadFeed,
    canon.TapFeed,
)


@dataclass
class Step:
    """One thing the channel does in order: queue an element, or act (`rest`: only with the
    path at rest; `wait`: the path then waits until it is done), or wait for an action."""

    line: int
    element: Element | None = None
    call: canon.Call | None = None
    rest: bool = False
    wait: bool = False
    waits_for: int | None = None  # wait (at rest) until this action is done
    action_id: int | None = None  # the number to start `call` with (None: a new one)
    dwell_s: float = 0.0
    block: int = 0  # the MDI block it belongs to (0 in a program)


@dataclass
class _Late:
    action_id: int
    until: str  # "feed" (MVS_SLM) or "end" (MVS_SLP)


@dataclass
class Execution:
    """The walk through one program's calls, or through MDI blocks as they come
    (`mdi_blocks`: each block's number and calls)."""

    calls: list[canon.Call]
    axes: tuple[str, ...]
    sync_of: Callable[[canon.Call], int]  # the synchronisation type of a spindle call
    ids: Callable[[], int]  # numbers for actions, unique in the machine
    rotary_axes: frozenset[str] = frozenset()  # in degrees: not part of the path length
    pc: int = 0  # next call to translate
    steps: deque[Step] = field(default_factory=deque)
    late: list[_Late] = field(default_factory=list)
    feed_mm_min: float | None = None
    plane: int = 17
    # G130-G133 in force, percent per axis (an axis not named: 100); feed blocks take them
    acceleration_weight: dict[str, float] = field(default_factory=dict)
    ramp_time_weight: dict[str, float] = field(default_factory=dict)
    # #VECTOR LIMIT in force, and how the channel turns it into mm/s and mm/s²
    vector_limit: canon.VectorLimit | None = None
    path_limits: Callable[[canon.VectorLimit], tuple[float, float, float]] | None = None
    parallel_manual: bool = False  # G201 in force [002 §2.6.2]
    mdi_blocks: deque[tuple[int, list[canon.Call]]] = field(default_factory=deque)
    block: int = 0  # the MDI block being translated

    def new_id(self) -> int:
        """A number for an action (what the host's `busy` is asked about)."""
        return self.ids()

    def more(self, position: list[float]) -> bool:
        """Translate the next block's calls into steps; False at the end of the calls.
        `position` is where the path will be when this block starts."""
        if self.pc >= len(self.calls):
            if not self.mdi_blocks:
                return False
            self.block, self.calls = self.mdi_blocks.popleft()
            self.pc = 0
            if not self.calls:  # a block of comments only
                return True
        line = self.calls[self.pc].line
        block: list[canon.Call] = []
        while self.pc < len(self.calls) and self.calls[self.pc].line == line:
            block.append(self.calls[self.pc])
            self.pc += 1
            if isinstance(block[-1], canon.RotaryMode):
                break  # the rest of the block starts where the changeover leaves C
        first = len(self.steps)
        self._translate(block, position)
        if self.block:
            for i in range(first, len(self.steps)):
                step = self.steps[i]
                step.block = self.block
                if step.element is not None:
                    step.element.block_id = self.block
        return True

    def __post_init__(self) -> None:
        self.linear = np.array([a not in self.rotary_axes for a in self.axes], dtype=float)

    def _translate(self, block: list[canon.Call], position: list[float]) -> None:
        has_motion = any(isinstance(c, _MOTION) for c in block)
        after: list[Step] = []
        start = np.array(position, dtype=float)
        for call in block:
            line = call.line
            match call:
                case canon.SetFeedRate():
                    self.feed_mm_min = call.feed_mm_min
                case canon.VectorLimit():  # a property of the blocks that follow
                    self.vector_limit = call
                case canon.Weighting():  # a property of the feed blocks that follow
                    self.acceleration_weight = dict(call.acceleration)
                    self.ramp_time_weight = dict(call.ramp_time)
                case canon.StraightTraverse() | canon.StraightFeed() | canon.ArcFeed():
                    is_feed = not isinstance(call, canon.StraightTraverse)
                    if is_feed:
                        for late in [x for x in self.late if x.until == "feed"]:
                            self.steps.append(Step(line, waits_for=late.action_id))
                            self.late.remove(late)
                    e = (
                        arc(self.axes, start, call, self.feed_mm_min, self.linear)
                        if isinstance(call, canon.ArcFeed)
                        else straight(
                            self.axes,
                            start,
                            call,
                            self.feed_mm_min,
                            self.linear,
                            self._radii(call) if isinstance(call, canon.StraightFeed) else None,
                        )
                    )
                    if e is not None:
                        g = 0 if not is_feed else 1
                        if isinstance(call, canon.ArcFeed):
                            g = 3 if call.turn > 0 else 2
                        e.modal = (g, self.plane, call.absolute, self.feed_mm_min)
                        if is_feed:
                            e.acceleration_weight = self._fractions(self.acceleration_weight)
                            e.ramp_time_weight = self._fractions(self.ramp_time_weight)
                        e.path_limit = self._path_limit(is_feed)
                        e.parallel_manual = self.parallel_manual
                        e.exact_stop = bool(after) or call.exact_stop
                        self.steps.append(Step(line, element=e))
                        start = e.end.copy()
                case canon.ThreadFeed() | canon.TapFeed():
                    for late in [x for x in self.late if x.until == "feed"]:
                        self.steps.append(Step(line, waits_for=late.action_id))
                        self.late.remove(late)
                    e = self._coupled(call, start)
                    if e is not None:
                        self.steps.append(Step(line, element=e))
                        start = e.end.copy()
                case canon.Dwell():
                    self.steps.append(Step(line, rest=True, dwell_s=call.time_s))
                case canon.ProgramEnd():
                    for late in self.late:
                        self.steps.append(Step(line, waits_for=late.action_id))
                    self.late.clear()
                    self.steps.append(Step(line, call=call, rest=True, wait=True))
                case (
                    canon.SpindleOn()
                    | canon.SpindleOff()
                    | canon.SpindleOrient()
                    | canon.SpindleSpeed()
                ):
                    self._spindle(call, has_motion, after)
                case canon.SelectPlane():
                    self.plane = call.plane
                    self.steps.append(Step(line, call=call))
                case canon.ManualMode():  # a property of the blocks that follow, and of jogs
                    self.parallel_manual = call.g == 201
                    self.steps.append(Step(line, call=call))
                case canon.SelectTool() | canon.SetSlope():
                    self.steps.append(Step(line, call=call))
                case _:  # gear change, homing, other M functions: at rest, waited for
                    self.steps.append(Step(line, call=call, rest=True, wait=True))
        self.steps.extend(after)

    def _radii(self, call: canon.StraightFeed) -> np.ndarray | None:
        """Each rotary axis' effective radius from RX/RY/RZ: the distance of the tool contact
        point from its axis of rotation (A about X, B about Y, C and the spindle as C about
        Z) [003 §1.2]; None without RX/RY/RZ."""
        if call.effective is None:
            return None
        rx, ry, rz = call.effective
        about = {"A": (ry, rz), "B": (rx, rz)}
        return np.array(
            [
                float(np.hypot(*about.get(a, (rx, ry)))) if a in self.rotary_axes else 0.0
                for a in self.axes
            ]
        )

    def _path_limit(self, is_feed: bool) -> tuple[float, float, float] | None:
        """The #VECTOR LIMIT of a feed or rapid block, None when none acts on it."""
        v = self.vector_limit
        if v is None or self.path_limits is None or not (v.feed if is_feed else v.rapid):
            return None
        return self.path_limits(v)

    def _fractions(self, percent: dict[str, float]) -> np.ndarray | None:
        """Per path axis as a fraction; None when every axis is at 100 %."""
        if all(v == 100.0 for v in percent.values()):
            return None
        return np.array([percent.get(a, 100.0) / 100.0 for a in self.axes])

    def _coupled(self, call: canon.ThreadFeed | canon.TapFeed, start: np.ndarray) -> Element | None:
        """The element of a G33/G63 block: a straight line whose path follows the spindle."""
        if isinstance(call, canon.TapFeed):
            e = straight(self.axes, start, call, call.feed_mm_min, self.linear)
            if e is None:
                return None
            pitch = call.feed_mm_min / abs(call.speed_rpm)
            e.coupling = Coupling(L.COUPLE_TAP, call.spindle, pitch, speed_rpm=call.speed_rpm)
            g = 63
        else:
            e = straight(self.axes, start, call, None, self.linear)
            if e is None:
                return None
            # the lead is measured along the pitch axis: path length per revolution
            along = abs(float(e.lin[self.axes.index(call.pitch_axis)]))
            pitch = call.pitch_mm / along if along > 1e-12 else call.pitch_mm
            e.coupling = Coupling(L.COUPLE_THREAD, call.spindle, pitch, offset_deg=call.offset_deg)
            g = 33
        e.modal = (g, self.plane, call.absolute, self.feed_mm_min)
        e.exact_stop = True  # it starts and ends at rest
        return e

    def _spindle(self, call: canon.Call, has_motion: bool, after: list[Step]) -> None:
        kind = sync_kind(call, self.sync_of(call))
        line = call.line
        if kind == "before" or (not has_motion and kind in ("after", "after_out")):
            self.steps.append(Step(line, call=call, rest=True, wait=True))
        elif kind == "none":
            self.steps.append(Step(line, call=call))
        elif kind == "after":  # MVS_SNS: out now, waited for after the block's motion
            aid = self.new_id()
            self.steps.append(Step(line, call=call, action_id=aid))
            after.append(Step(line, waits_for=aid))
        elif kind == "after_out":  # MNS_SNS: out and waited for after the block's motion
            after.append(Step(line, call=call, rest=True, wait=True))
        else:  # late: out now, waited for before the next feed block or at the end
            aid = self.new_id()
            self.steps.append(Step(line, call=call, action_id=aid))
            self.late.append(_Late(aid, "feed" if kind == "late_feed" else "end"))


def sync_kind(call: canon.Call, sync: int) -> str:
    """When a spindle call acts and is waited for, from its synchronisation type."""
    base = sync & ~PLC_INFO
    if base & MVS_SVS:
        return "before"
    if base & MVS_SNS:
        return "after"
    if base & (MNS_SNS | MNE_SNS):
        return "after_out"
    if base & MVS_SLM:
        return "late_feed"
    if base & MVS_SLP:
        return "late_end"
    if base & MOS:
        return "none"
    # NO_SYNCH: M3/M4/M5 synchronise internally on speed reached / standstill [000 §2.5.1],
    # M19 on in position; the S word alone does not wait (s_synch)
    return "none" if isinstance(call, canon.SpindleSpeed) else "before"


def describe(call: canon.Call, spindle_name: Callable[[str], str]) -> str:
    """What the path waits for, in the operator's words (spindles by their configured name)."""
    match call:
        case canon.SpindleOn():
            return f"speed reached of {spindle_name(call.spindle)} (M{call.m})"
        case canon.SpindleOff():
            return f"{spindle_name(call.spindle)} stopped (M5)"
        case canon.SpindleOrient():
            return f"{spindle_name(call.spindle)} in position (M19)"
        case canon.SpindleSpeed():
            return f"speed reached of {spindle_name(call.spindle)}"
        case canon.MFunction():
            return f"the PLC's acknowledgement of M{call.m}"
        case canon.SelectGear():
            return f"gear change M{call.stage + 39}"
        case canon.Home():
            return "homing (G74)"
        case canon.RotaryMode():
            into, ack = ("rotary axis", "ROTMOD_Q") if call.rotary else ("spindle", "SPMOD_Q")
            return f"changeover to {into} mode (the PLC's {ack})"
    return f"line {call.line}"
