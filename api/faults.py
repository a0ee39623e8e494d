"""Training faults an instructor injects into a machine: the catalogue of nc_sim/faults.py as
request and answer models (a union told apart by `kind`). Only instructors see them."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from api.common import unit

AXIS = Field(pattern=r"^[A-Z][A-Z0-9]{0,7}$", description="axis or spindle name")
FACTOR = Field(gt=0.01, le=100.0, description="factor against the correct value (1 = none)")


class _Fault(BaseModel):
    """A fault kind: its `title` is its name in the instructor's words (the console's fault
    form reads it from the OpenAPI schema)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class MotorInvertedModel(_Fault):
    """The motor is wired inverted: with the NC's signs unchanged the axis runs away."""

    model_config = ConfigDict(title="Motor wired inverted")
    kind: Literal["motor_inverted"] = "motor_inverted"
    axis: str = AXIS


class EncoderInvertedModel(_Fault):
    """The encoder counts inverted."""

    model_config = ConfigDict(title="Encoder counts inverted")
    kind: Literal["encoder_inverted"] = "encoder_inverted"
    axis: str = AXIS


class DriveGainWrongModel(_Fault):
    """The drive's speed per D/A digit is `factor` times what multi_gain assumes."""

    model_config = ConfigDict(title="Drive gain wrong")
    kind: Literal["drive_gain_wrong"] = "drive_gain_wrong"
    axis: str = AXIS
    factor: float = FACTOR


class EncoderResolutionWrongModel(_Fault):
    """The encoder delivers `factor` times the increments the NC's wegaufz/wegaufn assume."""

    model_config = ConfigDict(title="Encoder resolution wrong")
    kind: Literal["encoder_resolution_wrong"] = "encoder_resolution_wrong"
    axis: str = AXIS
    factor: float = FACTOR


class EncoderNoiseModel(_Fault):
    """White noise on the encoder's reading (seeded: reproducible)."""

    model_config = ConfigDict(title="Encoder noise")
    kind: Literal["encoder_noise"] = "encoder_noise"
    axis: str = AXIS
    rms: float = Field(
        gt=0, le=10.0, description="root mean square, mm | °", json_schema_extra=unit("mm")
    )
    seed: int = Field(1, ge=0, le=2**31 - 1)


class GearRatioWrongModel(_Fault):
    """One gear stage's mechanical ratio is `factor` times its gear record's."""

    model_config = ConfigDict(title="Gear ratio wrong")
    kind: Literal["gear_ratio_wrong"] = "gear_ratio_wrong"
    axis: str = AXIS
    gear: int = Field(ge=1, le=6, description="gear stage 1..6 (M40..M45 → getriebe[0..5])")
    factor: float = FACTOR


class FrictionModel(_Fault):
    """Coulomb friction: the drive loses `v_loss` against the motion, sticks below it."""

    model_config = ConfigDict(title="Friction")
    kind: Literal["friction"] = "friction"
    axis: str = AXIS
    v_loss: float = Field(
        gt=0, le=1000.0, description="speed lost, mm/s | °/s", json_schema_extra=unit("mm/s")
    )


class BacklashModel(_Fault):
    """Play between motor and load: a loose coupling."""

    model_config = ConfigDict(title="Backlash")
    kind: Literal["backlash"] = "backlash"
    axis: str = AXIS
    width: float = Field(gt=0, le=10.0, description="mm | °")


class CouplingSoftModel(_Fault):
    """The coupling's stiffness is `factor` times what it was: resonances sink by √factor."""

    model_config = ConfigDict(title="Coupling gone soft")
    kind: Literal["coupling_soft"] = "coupling_soft"
    axis: str = AXIS
    factor: float = Field(gt=0.01, lt=1.0, description="stiffness against the sound coupling")


class FrictionRisingModel(_Fault):
    """The guideways' friction torques are `factor` times what they were."""

    model_config = ConfigDict(title="Friction rising")
    kind: Literal["friction_rising"] = "friction_rising"
    axis: str = AXIS
    factor: float = Field(gt=1.0, le=100.0, description="friction against the sound guideways")


class NotchMistunedModel(_Fault):
    """The drive's current-setpoint filters act at `factor` times their set frequencies."""

    model_config = ConfigDict(title="Notch mistuned")
    kind: Literal["notch_mistuned"] = "notch_mistuned"
    axis: str = AXIS
    factor: float = FACTOR


class DriveAccelLimitModel(_Fault):
    """The drive is torque-limited: it accelerates no faster than `a_max`."""

    model_config = ConfigDict(title="Drive torque-limited")

    kind: Literal["drive_accel_limit"] = "drive_accel_limit"
    axis: str = AXIS
    a_max: float = Field(gt=0, le=1e6, description="mm/s² | °/s²")


class PlcNoAckModel(_Fault):
    """The PLC program never acknowledges M functions or mode requests."""

    model_config = ConfigDict(title="PLC never acknowledges")
    kind: Literal["plc_no_ack"] = "plc_no_ack"


class PlcSlowAckModel(_Fault):
    """The PLC program acknowledges only after `delay_s`."""

    model_config = ConfigDict(title="PLC acknowledges late")
    kind: Literal["plc_slow_ack"] = "plc_slow_ack"
    delay_s: float = Field(gt=0, le=600.0, description="simulated seconds")


class DriveNotReadyModel(_Fault):
    """The drive drops its ready signals."""

    model_config = ConfigDict(title="Drive not ready")
    kind: Literal["drive_not_ready"] = "drive_not_ready"
    axis: str = AXIS


class EnableDropModel(_Fault):
    """The PLC drops the axis' enable while it moves."""

    model_config = ConfigDict(title="Enable drops during motion")
    kind: Literal["enable_drop"] = "enable_drop"
    axis: str = AXIS


FaultModel = Annotated[
    MotorInvertedModel
    | EncoderInvertedModel
    | DriveGainWrongModel
    | EncoderResolutionWrongModel
    | EncoderNoiseModel
    | GearRatioWrongModel
    | FrictionModel
    | BacklashModel
    | CouplingSoftModel
    | FrictionRisingModel
    | NotchMistunedModel
    | DriveAccelLimitModel
    | PlcNoAckModel
    | PlcSlowAckModel
    | DriveNotReadyModel
    | EnableDropModel,
    Field(discriminator="kind"),
]


class TriggerModel(BaseModel):
    """When the fault takes effect: `after_s` simulated seconds after the injection, counted
    from the axis' next motion when `on_motion`. The default: at once."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    after_s: float = Field(0.0, ge=0, le=86_400, description="simulated seconds")
    on_motion: bool = False


class FaultInject(BaseModel):
    """A fault to inject, now or at a trigger."""

    fault: FaultModel
    trigger: TriggerModel = Field(default_factory=TriggerModel)


class FaultInfo(BaseModel):
    """An injected fault of a machine."""

    id: int
    fault: FaultModel
    trigger: TriggerModel
    injected_s: float = Field(description="simulated time of the injection, s")
    active: bool = Field(description="false while its trigger is armed")
    active_since_s: float | None = Field(description="simulated time it took effect, s")
    text: str = Field(description="what it is in words, for the console")
