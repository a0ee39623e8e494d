"""Faults of the simulated plant and PLC, for training: what an instructor injects into a
student's machine.

A fault changes the simulated machine (motor, encoder, drive, mechanics, PLC program), never a
parameter the student sees: finding it is the exercise. Each kind is its own frozen dataclass
(typed, like the commands); `Trigger` says when an injected fault takes effect. Positions and
distances are in the axis' unit (mm | °), as the commands have them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar


@dataclass(frozen=True)
class MotorInverted:
    """The motor is wired inverted: the drive turns the other way than commanded. With the
    NC's signs as they were, the position loop has positive feedback: the axis runs away
    until lag monitoring trips."""

    kind: ClassVar[str] = "motor_inverted"
    axis: str


@dataclass(frozen=True)
class EncoderInverted:
    """The encoder counts inverted (the actual value's sign is wrong)."""

    kind: ClassVar[str] = "encoder_inverted"
    axis: str


@dataclass(frozen=True)
class DriveGainWrong:
    """The drive's speed for a given D/A value is `factor` times what it was: the measured
    gain k becomes factor·kv (multi_gain no longer matches the drive)."""

    kind: ClassVar[str] = "drive_gain_wrong"
    axis: str
    factor: float


@dataclass(frozen=True)
class EncoderResolutionWrong:
    """The encoder delivers `factor` times the increments per unit that the NC's wegaufz/
    wegaufn assume: the NC reads factor × the true position."""

    kind: ClassVar[str] = "encoder_resolution_wrong"
    axis: str
    factor: float


@dataclass(frozen=True)
class EncoderNoise:
    """White noise on the encoder's reading, `rms` (mm | °) root mean square, from a
    seeded generator (the same seed, the same noise: runs stay reproducible)."""

    kind: ClassVar[str] = "encoder_noise"
    axis: str
    rms: float
    seed: int = 1


@dataclass(frozen=True)
class GearRatioWrong:
    """Gear stage `gear` (1-based, as getriebe[gear-1]) of a spindle has a mechanical ratio
    `factor` times what its gear record says: in that gear only, the drive's true gain is
    factor times the gear record's."""

    kind: ClassVar[str] = "gear_ratio_wrong"
    axis: str
    gear: int
    factor: float


@dataclass(frozen=True)
class Friction:
    """Coulomb friction: the drive loses `v_loss` (mm | ° per s) of speed against the motion
    and sticks while its command is below that."""

    kind: ClassVar[str] = "friction"
    axis: str
    v_loss: float


@dataclass(frozen=True)
class Backlash:
    """Play of `width` (mm | °) between motor and load, a loose coupling; the ideal plant's
    encoder reads the load, the drive cascade's measuring system is where its list says."""

    kind: ClassVar[str] = "backlash"
    axis: str
    width: float


@dataclass(frozen=True)
class CouplingSoft:
    """The coupling between motor and load has gone soft: its stiffness is `factor` (< 1)
    times what it was, so the anti-resonance and the resonance sink by √factor (the drive
    cascade's two-mass mechanics; a rigid axis has no coupling to soften)."""

    kind: ClassVar[str] = "coupling_soft"
    axis: str
    factor: float


@dataclass(frozen=True)
class FrictionRising:
    """The guideways' friction (Coulomb and breakaway torque of the drive cascade's
    mechanics) is `factor` times what it was: reversal spikes grow, a P speed loop loses
    more speed."""

    kind: ClassVar[str] = "friction_rising"
    axis: str
    factor: float


@dataclass(frozen=True)
class NotchMistuned:
    """The drive's current-setpoint filters act at `factor` times the frequencies their
    parameters give (as after a change of the drive's sampling the filters were not set up
    for): a notch misses the resonance it was put on."""

    kind: ClassVar[str] = "notch_mistuned"
    axis: str
    factor: float


@dataclass(frozen=True)
class DriveAccelLimit:
    """The drive is torque-limited: it cannot accelerate the axis faster than `a_max`
    (mm/s² | °/s²), whatever the NC's ramp asks. A ramp steeper than that leaves the drive
    behind and the lag grows [000 §2.8.4]."""

    kind: ClassVar[str] = "drive_accel_limit"
    axis: str
    a_max: float


@dataclass(frozen=True)
class PlcNoAck:
    """The PLC program never acknowledges M functions or mode requests (the NC's handshake
    times out with job error 90004), whatever PLC mode the HLI shows."""

    kind: ClassVar[str] = "plc_no_ack"


@dataclass(frozen=True)
class PlcSlowAck:
    """The PLC program acknowledges only after `delay_s` simulated seconds."""

    kind: ClassVar[str] = "plc_slow_ack"
    delay_s: float


@dataclass(frozen=True)
class DriveNotReady:
    """The drive drops its ready signals (a drive fault): the control loop opens."""

    kind: ClassVar[str] = "drive_not_ready"
    axis: str


@dataclass(frozen=True)
class EnableDrop:
    """The PLC drops the axis' enable (TorquePermission) while it moves."""

    kind: ClassVar[str] = "enable_drop"
    axis: str


Fault = (
    MotorInverted
    | EncoderInverted
    | DriveGainWrong
    | EncoderResolutionWrong
    | EncoderNoise
    | GearRatioWrong
    | Friction
    | Backlash
    | CouplingSoft
    | FrictionRising
    | NotchMistuned
    | DriveAccelLimit
    | PlcNoAck
    | PlcSlowAck
    | DriveNotReady
    | EnableDrop
)
CATALOGUE: tuple[type[Fault], ...] = (
    MotorInverted,
    EncoderInverted,
    DriveGainWrong,
    EncoderResolutionWrong,
    EncoderNoise,
    GearRatioWrong,
    Friction,
    Backlash,
    CouplingSoft,
    FrictionRising,
    NotchMistuned,
    DriveAccelLimit,
    PlcNoAck,
    PlcSlowAck,
    DriveNotReady,
    EnableDrop,
)


@dataclass(frozen=True)
class Trigger:
    """When an injected fault takes effect: `after_s` simulated seconds after it was
    injected, counted from the moment its axis next moves when `on_motion` (a fault without
    an axis ignores `on_motion`). The default is at once."""

    after_s: float = 0.0
    on_motion: bool = False


NOW = Trigger()


@dataclass(frozen=True)
class FaultState:
    """An injected fault as the instructor sees it."""

    id: int
    fault: Fault
    trigger: Trigger
    injected_cycle: int
    active_since: int | None  # cycle it took effect, None while its trigger is armed
