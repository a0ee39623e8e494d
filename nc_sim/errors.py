"""Job errors and events: numbered as the manuals number them, ours where they give none.

Expected outcomes (a refused command, a monitor that trips) are `Event` values
(nc_sim/events.py) in the HLI and the event log; misuse of the API raises `NcUsageError`.
"""

from __future__ import annotations

from enum import IntEnum


class Code(IntEnum):
    """Error and event numbers. 6xxxx/7xxxx from the spindle manual, 9xxxx ours."""

    SPINDLE_PREFERRED_DIRECTION = 60254  # [000 §2.6] commanded direction violates vorz_richtung
    SPINDLE_SENSORLESS_M19 = 70252  # [000 §2.2.4] a sensorless spindle cannot be positioned
    NO_ENABLES = 90001
    LAG_MONITORING = 90002
    SOFTWARE_LIMIT = 90003
    PLC_ACK_TIMEOUT = 90004
    EMERGENCY_STOP = 90005
    AXIS_BUSY = 90006
    DRIVE_NOT_READY = 90007
    ENABLES_LOST = 90008
    BLOCK_SYNTAX = 90010
    UNKNOWN_AXIS = 90011
    NOT_SUPPORTED = 90012
    NOT_HOMED = 90013
    FEED_MISSING = 90014
    CHANNEL_ERROR_STATE = 90015
    GEAR_NO_RANGE = 90017
    GEAR_WRONG_STAGE = 90018
    GEAR_NOT_PROGRAMMED = 90019
    GEAR_CHANGE_OFF = 90020
    SPINDLE_NOT_HOMED = 90021
    NOT_A_SPINDLE = 90022
    SEQUENCE_WATCHDOG = 90023
    CURVE_NO_ACCELERATION = 90024
    JOG_FEED_TOO_HIGH = 90025  # [002 §2.6.1] above the G200 maximum handbetrieb.hb.vb_max
    ARC_GEOMETRY = 90026  # G02/G03 whose start and end radii differ, or no centre or radius
    PROGRAM_STRUCTURE = 90027  # subprogram undefined or not ended, no program end, nesting
    FEEDHOLD_ACTIVE = 90028  # cycle start while the HLI feedhold holds the channel
    THREAD_NOT_POSSIBLE = 90029  # [000 §2.8.7] G33 without a rotating, measured spindle, ...
    TAPPING_NOT_POSSIBLE = 90030  # [000 §2.8.6] G63 with a turning spindle, no encoder, ...
    MODE_ACK_WITHDRAWN = 90031  # [003 §4.1] ROTMOD_Q/SPMOD_Q withdrawn in its mode: process error
    CHANGEOVER_NOT_POSSIBLE = 90032  # [003 §4.2] spindle <-> C axis: no encoder, in error, ...
    # events (information, not errors)
    EV_BLOCK_DONE = 10
    EV_M_OUTPUT = 11
    EV_M_ACK = 12
    EV_HOMED = 13
    EV_RESET = 14
    EV_SPEED_REACHED = 15
    EV_HLI = 16
    EV_PLC_MODE = 17
    EV_MOTION_DONE = 18
    EV_LOOP_OPENED = 19
    EV_LOOP_CLOSED = 20
    EV_REFERENCE_LOST = 21
    EV_GEAR_CHANGED = 22
    EV_IN_POSITION = 23
    EV_TOOL_DYNAMICS = 24
    EV_PROGRAM_END = 25
    EV_M_START = 26  # a spindle M function begins; it acts from the next cycle on
    EV_POWERED = 27  # power-on done: every drive switched on and reporting ready
    EV_GEAR_CHANGE_START = 28  # a gear change begins (to the change position, then M4x)
    EV_PROGRAM_LOADED = 29
    EV_PROGRAM_START = 30  # cycle start of a program
    EV_PROGRAM_STOP = 31  # stopped by the operator, rewound
    EV_COUPLED = 32  # G33/G63: the path follows the spindle
    EV_SIGNAL_ON = 33  # a PLC interface signal (Event.signal: ROTMOD, ROTMOD_Q, ...) goes to 1
    EV_SIGNAL_OFF = 34  # ... goes to 0
    EV_CHANGEOVER = 35  # [003 Fig. 4-1 (1)] spindle <-> rotary axis changeover activated
    EV_CHANGEOVER_INTERNAL = 36  # (2) decelerated, speed control, drive parameter record
    EV_CHANGEOVER_END = 37  # (4) the PLC's external changeover ended: de-activated
    EV_ROTARY_MODE = 38  # (5)+(6) position control: the main spindle is the rotary axis C
    EV_SPINDLE_MODE = 39  # (5)+(6) the main spindle is a spindle again
    EV_CHANGEOVER_INTERRUPTED = 40  # [003 §2.3] immediate stop: the changeover stays pending
    EV_CHANGEOVER_ABORTED = 41  # reset, or a jog/M3/M4/M5/M19 key, ends it
    EV_BLOCK_DROPPED = 42  # a job error ended an MDI block before it was done (value: its seq)


MESSAGES: dict[Code, str] = {
    Code.SPINDLE_PREFERRED_DIRECTION: "commanded direction of rotation violates the preferred "
    "direction (P-AXIS-00224/P-AXIS-00031)",
    Code.SPINDLE_SENSORLESS_M19: "a sensorless spindle cannot be positioned (M19)",
    Code.NO_ENABLES: "drive enables missing: motion refused",
    Code.LAG_MONITORING: "lag monitoring: position lag exceeds its limit (getriebe[i].lag_max)",
    Code.SOFTWARE_LIMIT: "target beyond the software limit (P-AXIS-00177/P-AXIS-00178)",
    Code.PLC_ACK_TIMEOUT: "the PLC did not acknowledge the M function or mode request in time",
    Code.EMERGENCY_STOP: "emergency stop",
    Code.AXIS_BUSY: "axis is moving: command refused",
    Code.DRIVE_NOT_READY: "drive not ready (drive status): motion refused",
    Code.ENABLES_LOST: "drive enables removed during motion",
    Code.BLOCK_SYNTAX: "NC block syntax error",
    Code.UNKNOWN_AXIS: "no such axis or spindle in the channel",
    Code.NOT_SUPPORTED: "command not supported",
    Code.NOT_HOMED: "axis not homed: programmed motion needs homing first (P-AXIS-00277)",
    Code.FEED_MISSING: "G01 needs a feed F > 0",
    Code.CHANNEL_ERROR_STATE: "channel in error state: reset first",
    Code.GEAR_NO_RANGE: "spindle speed out of reach",
    Code.GEAR_WRONG_STAGE: "wrong gear stage: S is outside the programmed M40-M45 range",
    Code.GEAR_NOT_PROGRAMMED: "no gear stage programmed: S is outside the current range",
    Code.GEAR_CHANGE_OFF: "gear change M40-M45 is not enabled (P-CHAN-00052) or not the "
    "main spindle",
    Code.SPINDLE_NOT_HOMED: "spindle not homed and automatic homing is off "
    "(ACHSMODE_KEINE_AUTO_RPF): home with G74 first",
    Code.NOT_A_SPINDLE: "spindle command to an axis that is not a spindle",
    Code.SEQUENCE_WATCHDOG: "watchdog: a sequence did not end within the bound derived from "
    "its own parameters; it is braked and the axis is in error",
    Code.CURVE_NO_ACCELERATION: "the acceleration curve (P-AXIS-00202) gives no usable "
    "acceleration on the way to the commanded speed: speed change refused",
    Code.JOG_FEED_TOO_HIGH: "jog feed above the manual-mode maximum velocity (G200, "
    "P-AXIS-00213): jog refused",
    Code.ARC_GEOMETRY: "circle not possible: start and end radius differ, or no centre (I/J/K) "
    "or radius (R) programmed",
    Code.PROGRAM_STRUCTURE: "program structure: subprogram not defined or without M17/M29, "
    "program without M30/M02, or subprograms nested too deep",
    Code.FEEDHOLD_ACTIVE: "feedhold is on: the channel goes on when feedhold is released",
    Code.THREAD_NOT_POSSIBLE: "thread cutting G33 not possible: the spindle must rotate "
    "(M3/M4) with its encoder, the thread's feed must be within the axes' limits and the "
    "thread long enough to accelerate and brake",
    Code.TAPPING_NOT_POSSIBLE: "tapping G63 not possible: the spindle must stand (M5 or M19 "
    "first) and be position-controlled, and the feed within the axes' limits",
    Code.MODE_ACK_WITHDRAWN: "the PLC withdrew the acknowledgement of the mode in force "
    "(ROTMOD_Q/SPMOD_Q): process error",
    Code.CHANGEOVER_NOT_POSSIBLE: "changeover between spindle and rotary axis not possible",
    Code.EV_BLOCK_DONE: "block done",
    Code.EV_M_OUTPUT: "M function output to the PLC",
    Code.EV_M_ACK: "M function acknowledged by the PLC",
    Code.EV_HOMED: "homed",
    Code.EV_RESET: "CNC reset",
    Code.EV_SPEED_REACHED: "speed reached",
    Code.EV_HLI: "HLI control unit written",
    Code.EV_PLC_MODE: "PLC mode changed",
    Code.EV_MOTION_DONE: "motion done: the set-point is at its target",
    Code.EV_LOOP_OPENED: "position loop opened",
    Code.EV_LOOP_CLOSED: "position loop closed",
    Code.EV_REFERENCE_LOST: "reference lost above the control limit: the spindle is homed "
    "again before positioning",
    Code.EV_GEAR_CHANGED: "gear stage changed",
    Code.EV_IN_POSITION: "in position",
    Code.EV_TOOL_DYNAMICS: "tool dynamics",
    Code.EV_PROGRAM_END: "program end: the last block's set-point has ended",
    Code.EV_M_START: "spindle M function started",
    Code.EV_POWERED: "machine ready: the PLC has switched every drive on",
    Code.EV_GEAR_CHANGE_START: "gear change started",
    Code.EV_PROGRAM_LOADED: "program loaded",
    Code.EV_PROGRAM_START: "program started",
    Code.EV_PROGRAM_STOP: "program stopped",
    Code.EV_COUPLED: "path coupled to the spindle",
    Code.EV_SIGNAL_ON: "PLC signal set",
    Code.EV_SIGNAL_OFF: "PLC signal reset",
    Code.EV_CHANGEOVER: "changeover between spindle and rotary axis activated",
    Code.EV_CHANGEOVER_INTERNAL: "internal changeover done",
    Code.EV_CHANGEOVER_END: "changeover de-activated",
    Code.EV_ROTARY_MODE: "rotary axis mode",
    Code.EV_SPINDLE_MODE: "spindle mode",
    Code.EV_CHANGEOVER_INTERRUPTED: "changeover interrupted",
    Code.EV_CHANGEOVER_ABORTED: "changeover aborted",
    Code.EV_BLOCK_DROPPED: "MDI block dropped by a job error",
}
"""What each code means, in the operator's words; every code has one (the event log shows it
when an event carries no detail of its own)."""


def is_error(code: int) -> bool:
    """True for job errors, false for informational events."""
    return code >= 60000


class NcUsageError(ValueError):
    """Misuse of the simulation API (not a machine condition)."""
