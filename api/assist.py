"""Commissioning assistants [004 §3.5, §3.6]: what to run, and what they answer."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field

from api.commands import AxisName


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
    distance: float = Field(1.0, ge=-100, le=100, description="mm (° for rotary)")
    feed_mm_min: float = Field(100.0, gt=0, le=1e5, description="mm/min (°/min)")
    observed: Literal[1, -1] | None = None


KvPerS = Annotated[float, Field(gt=0, le=10000, description="kv, 1/s")]


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
        None, gt=0, le=100, description="G00 step, mm (° for rotary); null: 20 exact-stop windows"
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
