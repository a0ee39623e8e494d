"""What the training faults in force change in an axis' plant (the plant itself:
nc_sim/axis/plant.py)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class PlantFaults:
    """What the faults in force change in one axis' plant; the default is a sound plant."""

    motor_inverted: bool = False  # the motor turns against the drive's command
    encoder_inverted: bool = False  # the encoder counts the other way
    speed_factor: float = 1.0  # the drive's speed per D/A digit, times this
    gear_factors: dict[int, float] = field(default_factory=dict)  # gear -> mechanical ratio ×
    encoder_factor: float = 1.0  # the encoder counts this times the true position
    noise_rms: float = 0.0  # white noise on the encoder's reading (mm | °)
    friction: float = 0.0  # Coulomb friction: speed lost against the motion (unit/s)
    backlash: float = 0.0  # play between motor and load (mm | °)
    a_max: float = 0.0  # the drive accelerates no faster than this (unit/s²), 0 = its own
    # the drive cascade's mechanics and filters (nc_sim/plant)
    stiffness_factor: float = 1.0  # the coupling's stiffness × this
    friction_factor: float = 1.0  # Coulomb and breakaway torque × this
    filter_factor: float = 1.0  # the current-setpoint filters act at their frequencies × this
