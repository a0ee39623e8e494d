"""Commissioning assistants [004 §3.5, §3.6]: what to run, and what they answer."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, field_validator, model_validator

from api.commands import AxisName
from api.common import unit


class MultiGainRequest(BaseModel):
    """multi_gain by experiment (004 §3.6.2): an axis at constant feed, or a spindle turning
    position-controlled at constant speed; the lag averaged over `window_s`."""

    axis: AxisName
    feed_mm_min: float | None = Field(
        None, gt=0, le=1e6, description="axis feed, mm/min (°/min for a rotary axis)"
    )
    speed_rpm: float | None = Field(None, gt=0, le=1e5, description="spindle speed, rpm")
    window_s: float = Field(1.0, ge=0.2, le=30, description="averaged over, s")
    direction: Literal[1, -1] = 1


class SignCheckRequest(BaseModel):
    """The sign check (004 §3.5): a short move; `observed` is the way the machine moved as
    the engineer saw it (+1 as commanded, -1 the other way; null: the simulated plant's)."""

    axis: AxisName
    distance: float = Field(
        1.0, ge=-100, le=100, description="mm (° for rotary)", json_schema_extra=unit("mm")
    )
    feed_mm_min: float = Field(100.0, gt=0, le=1e5, description="mm/min (°/min)")
    observed: Literal[1, -1] | None = None


KvPerS = Annotated[
    float, Field(gt=0, le=10000, description="kv, 1/s", json_schema_extra=unit("1/s"))
]


class LoopGainRequest(BaseModel):
    """The position loop gain sweep (004 §3.6): at each kv a G00 step and a G01 ramp on a
    copy; the highest kv whose step overshoots at most `overshoot_pct` and settles into the
    exact-stop window within `settle_ms` is proposed."""

    axis: AxisName
    kvs: list[KvPerS] | None = Field(
        None, min_length=1, max_length=12, description="kv values to try, 1/s (null: 0.5×-3×)"
    )
    overshoot_pct: float = Field(5.0, ge=0, le=100, description="target: step overshoot, %")
    settle_ms: float = Field(200.0, gt=0, le=10000, description="target: step settling, ms")
    step: float | None = Field(
        None,
        gt=0,
        le=100,
        description="G00 step, mm (° for rotary); null: 20 exact-stop windows",
        json_schema_extra=unit("mm"),
    )
    feed_mm_min: float | None = Field(
        None, gt=0, le=1e5, description="G01 ramp feed, mm/min (°/min); null: 5 % of rapid"
    )
    direction: Literal[1, -1] = 1


class LiveCancel(BaseModel):
    """End the live run now (its motion brakes as at a CNC reset; a spindle stops with M5)."""

    why: str = Field("cancelled by the engineer", max_length=200)


class AssistProgress(BaseModel):
    """A live assistant run as everyone watching the machine sees it (simulated seconds)."""

    name: str
    axis: str
    phase: str = Field(description="what the machine does now")
    elapsed_s: float
    planned_s: float = Field(description="the run's expected length as known now")
    by: str = Field(description="who started it")


class AssistFigure(BaseModel):
    name: str
    value: float
    unit: str
    text: str = ""


class AssistChange(BaseModel):
    """A proposed parameter change, in raw list units (as PATCH parameters takes it)."""

    target: str = Field(description="axis name, or channel")
    parameter: str = Field(description="list name, e.g. getriebe[0].multi_gain_z")
    before: float | int | str
    after: float | int | str
    why: str = ""


class AssistSeries(BaseModel):
    name: str
    x: list[float]
    y: list[float]
    x_unit: str = ""
    y_unit: str = ""


class AssistResult(BaseModel):
    """An assistant's answer: measured figures, proposed changes, plot series, notes. `ok`
    false: the run found a fault the changes do not cure (the notes say which)."""

    assistant: str
    ok: bool
    inputs: dict[str, float | int | str]
    figures: list[AssistFigure]
    changes: list[AssistChange]
    series: list[AssistSeries]
    notes: list[str]


# --- the calculators (004 §3.4, §3.6.1, 000 §2.2.4, §2.8.4) and the gear ranges (000 §2.8.2):
# pure arithmetic on the inputs; the machine only supplies the values "before".

GearStage = Annotated[int, Field(ge=1, le=6, description="gear stage 1-6 (M40-M45, getriebe[0-5])")]
GearRatio = Annotated[
    float, Field(gt=0, le=1e6, description="i: motor revolutions per output revolution")
]


class ResolutionRequest(BaseModel):
    """wegaufz/wegaufn (004 §3.4): a linear axis gives `pitch_mm`, a rotary axis or spindle
    sets `rotary` (360° per revolution) — exactly one of the two."""

    axis: AxisName
    gear: GearStage = 1
    increments_per_rev: int = Field(
        gt=0, le=4294967295, description="encoder increments per motor revolution"
    )
    pitch_mm: float | None = Field(None, gt=0, le=1e4, description="mm per output revolution")
    rotary: bool = False
    gear_ratio: GearRatio = 1.0


class MultiGainCalcRequest(BaseModel):
    """multi_gain by calculation (004 §3.6.1): exactly one drive scaling — `digits_per_rpm`,
    the D/A full scale (`full_scale_digits` at `full_scale_rpm`), or a SERCOS weighting
    (`speed_weighting_rpm` rotary, `speed_weighting_m_per_min` translatory). No `pitch_mm`:
    rotary (1000 °/min), else linear (1 m/min)."""

    axis: AxisName
    gear: GearStage = 1
    digits_per_rpm: float | None = Field(
        None, gt=0, le=1e9, description="digits per motor rpm", json_schema_extra=unit("digits/rpm")
    )
    full_scale_digits: int | None = Field(
        None, gt=0, le=2147483647, description="command value at full scale, digits"
    )
    full_scale_rpm: float | None = Field(None, gt=0, le=1e6, description="motor rpm at full scale")
    speed_weighting_rpm: float | None = Field(
        None,
        gt=0,
        le=1e3,
        description="SERCOS rotary weighting, rpm per digit",
        json_schema_extra=unit("rpm/digit"),
    )
    speed_weighting_m_per_min: float | None = Field(
        None,
        gt=0,
        le=1e3,
        description="SERCOS translatory weighting, m/min per digit",
        json_schema_extra=unit("m/min/digit"),
    )
    pitch_mm: float | None = Field(None, gt=0, le=1e4, description="mm per output revolution")
    gear_ratio: GearRatio = 1.0


class SpeedScalingRequest(BaseModel):
    """v_reso_num/v_reso_denom of a speed-controlled spindle (000 §2.2.4): `increments`
    output turn the motor at `speed_rpm`; time base 0 minute, 1 second, 2 cycle."""

    axis: AxisName
    increments: int = Field(gt=0, le=4294967295, description="value output to the drive")
    speed_rpm: float = Field(gt=0, le=1e6, description="motor speed at that value, rpm")
    time_base: Literal[0, 1, 2] = 0
    cycle_ms: float | None = Field(None, gt=0, le=1000, description="cycle time (time base 2), ms")
    gear_ratio: GearRatio = 1.0


class CurvePoint(BaseModel):
    n_deg_s: float = Field(ge=0, le=1e7, description="speed n, °/s")
    a_deg_s2: float = Field(gt=0, le=1e9, description="acceleration a, °/s²")


class CurveFitRequest(BaseModel):
    """The acceleration curve (000 §2.8.4) of type `typ` (1 hyperbola, 2 polynomial,
    3 asynchronous) from points: 4 (polynomial) or 3 (hyperbola) are interpolated with the
    first as (n_limit, a_konst), more are fitted by least squares."""

    axis: AxisName = Field(description="the spindle")
    gear: GearStage = 1
    typ: Literal[1, 2, 3] = 2
    points: list[CurvePoint] = Field(min_length=3, max_length=500)
    n_limit_deg_s: float | None = Field(None, gt=0, le=1e7, description="limit speed, °/s")
    a_min: float = Field(
        0.0, ge=0, le=1e9, description="the curve's floor, °/s²", json_schema_extra=unit("°/s²")
    )


class CurveRunUpRequest(BaseModel):
    """Run the spindle up with M3 in `gear` on a copy of the machine and fit `typ` to the
    measured a(n) (000 §2.8.4)."""

    axis: AxisName = Field(description="the spindle")
    gear: GearStage = 1
    typ: Literal[1, 2, 3] = 2
    speed_rpm: float | None = Field(None, gt=0, le=1e5, description="top speed (default vb_max)")
    n_limit_deg_s: float | None = Field(None, gt=0, le=1e7, description="limit speed, °/s")


class GearRangeValues(BaseModel):
    """One speed range (P-CHAN-00058 min_speed, P-CHAN-00055 max_speed); 0/0: unused."""

    min_rpm: int = Field(ge=0, le=65535, description="min_speed, rpm")
    max_rpm: int = Field(ge=0, le=65535, description="max_speed, rpm")

    @model_validator(mode="after")
    def _ordered(self) -> GearRangeValues:
        if self.max_rpm and self.min_rpm > self.max_rpm:
            raise ValueError(f"min_rpm {self.min_rpm} is above max_rpm {self.max_rpm}")
        return self


class GearSelectionRequest(BaseModel):
    """The gear stages of the main spindle (000 §2.8.2) as edited, and speeds S to preview the
    selection for, in order (each runs in the stage the one before chose). Unset: the
    machine's own table, search direction, automatic mode and current stage."""

    ranges: list[GearRangeValues] | None = Field(None, min_length=6, max_length=6)
    speeds_rpm: list[float] = Field(
        default_factory=list, max_length=50, description="programmed speeds S, rpm"
    )
    current_gear: GearStage | None = None
    range_way: Literal[0, 1] | None = Field(None, description="0 bottom-up, 1 top-down")
    automatic: bool | None = Field(None, description="autom_range (P-CHAN-00004)")

    @field_validator("speeds_rpm")
    @classmethod
    def _speeds(cls, v: list[float]) -> list[float]:
        for s in v:
            if not -1e5 <= s <= 1e5:
                raise ValueError(f"S{s:g} is out of range (|S| ≤ 100000 rpm)")
        return v


class GearStep(BaseModel):
    """One S of the preview: the stage the rule selects (and the M function output if it
    changes), or the job error that refuses it."""

    speed_rpm: float
    gear: int | None
    m: int | None = Field(description="M40-M45 of the selected stage")
    change: bool = Field(description="a gear change (M4x to the PLC)")
    error: str = ""
    detail: str = ""


class GearSelectionResult(BaseModel):
    spindle: str
    spindle_index: int = Field(description="i of spindel[i] in the channel list")
    gear_change: bool = Field(description="main_spindle_gear_change (P-CHAN-00052)")
    automatic: bool
    range_way: int
    current_gear: int
    ranges: list[GearRangeValues]
    steps: list[GearStep]
    changes: list[AssistChange] = Field(description="the edited ranges against the machine's")
