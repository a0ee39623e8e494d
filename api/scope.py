"""The scope and the trace library: capture setup, status, traces, measurements, recordings.

A capture's data travels as one binary frame (the telemetry format of api/telemetry.py, every
cycle, `stride` 1). Times of a trace are relative to its trigger: sample k of a capture with
`first_cycle` f and `trigger_cycle` c is at `(f + k - c) * cycle_s` seconds.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from api.common import JobErrorModel

MAX_CHANNELS = 16
MAX_LENGTH_S = 60.0
MAX_DRIVE_LENGTH_S = 2.0  # a drive-rate capture: a drive's trace memory (16 000 samples)
EventName = Literal["m_start", "m19_done", "gear_change", "job_error", "speed_reached"]


class LevelTriggerModel(BaseModel):
    """Fire when a signal crosses a level; it must first be beyond level ∓ hysteresis."""

    type: Literal["level"] = "level"
    signal: str = Field(description="`<axis>.<signal>`, any signal of the machine")
    level: float = Field(description="in the signal's display unit")
    edge: Literal["rising", "falling"] = "rising"
    hysteresis: float = Field(0.0, ge=0, description="in the signal's display unit")


class EventTriggerModel(BaseModel):
    """Fire on an NC event: M function start, M19 done, gear change, job error, speed reached."""

    type: Literal["event"] = "event"
    event: EventName
    axis: str | None = Field(None, description="only this axis or spindle (null: any)")
    m: int | None = Field(None, ge=0, le=99, description="m_start only: which M (null: any)")


TriggerModel = Annotated[LevelTriggerModel | EventTriggerModel, Field(discriminator="type")]


class ScopeSetupModel(BaseModel):
    """What the scope records and when it captures."""

    channels: list[str] = Field(min_length=1, max_length=MAX_CHANNELS)
    length_s: float = Field(1.0, gt=0, le=MAX_LENGTH_S, description="record length, s")
    pretrigger_pct: float = Field(20.0, ge=0, le=100, description="share before the trigger")
    mode: Literal["roll", "normal", "single"] = "single"
    trigger: TriggerModel | None = Field(None, description="required unless mode is roll")
    take_over: bool = Field(
        False,
        description="re-arm a scope another person armed and is still using (its holder of "
        "control, instructors and admins may; they are told): without it that is refused",
    )
    rate: Literal["nc", "drive"] = Field(
        "nc",
        description=(
            "nc: every NC cycle, any signals; drive: every drive step (e.g. 125 µs), the drive "
            "signals of one axis on the drive cascade (`<axis>.drive.*`, see the status' "
            f"drive_channels), single or normal mode, up to {MAX_DRIVE_LENGTH_S:g} s; the "
            "trigger is the NC's as ever"
        ),
    )


class ChannelInfo(BaseModel):
    name: str
    unit: str
    kind: Literal["float", "bool", "enum"]


class TraceInfo(BaseModel):
    """A capture (kept in memory until saved) or a trace of the library."""

    model_config = ConfigDict(allow_inf_nan=False)  # a stored NaN would break the library

    id: str
    machine: str
    machine_name: str
    name: str
    notes: str
    source: Literal["capture", "import", "flight"] = Field(
        description="a scope capture, an imported file, or the flight recorder's"
    )
    stored: bool = Field(description="saved in the library (else one of the recent captures)")
    trigger: str = Field(description="what triggered it, e.g. 'M19 start on S1'")
    forced: bool
    created_unix: float = Field(description="wall time the capture completed (or was imported)")
    first_cycle: int
    trigger_cycle: int | None
    count: int = Field(description="samples per channel, one per cycle")
    cycle_s: float
    channels: list[ChannelInfo]
    params_changed: int = Field(description="parameters that differed from their defaults")


class ParamValueAt(BaseModel):
    """A parameter that differed from its default when the trace was captured."""

    model_config = ConfigDict(allow_inf_nan=False)

    scope: str
    target: str
    name: str
    value: float | int | str
    default: float | int | str | None


class TraceDetail(TraceInfo):
    params: list[ParamValueAt]
    events: list[JobErrorModel] = Field(description="events and job errors in the record")


class TraceSave(BaseModel):
    name: str = Field("", max_length=120)
    notes: str = Field("", max_length=4000)


class TracePatch(BaseModel):
    name: str | None = Field(None, max_length=120)
    notes: str | None = Field(None, max_length=4000)


class MeasurementsModel(BaseModel):
    """Step-response figures of one channel between t0_s and t1_s (s from the trigger)."""

    channel: str
    unit: str
    t0_s: float
    t1_s: float
    samples: int
    initial: float
    final: float = Field(description="steady mean: mean of the last 10 % of the window")
    minimum: float
    maximum: float
    max_abs: float = Field(description="largest |value|, e.g. the maximum lag")
    t_max_abs_s: float
    mean: float
    overshoot_pct: float | None = Field(description="beyond the final value, % of the step")
    rise_time_s: float | None = Field(description="10 % → 90 % of the step")
    settling_time_s: float | None = Field(
        description="from the trigger (or window start) until it stays in final ± band"
    )
    band: float = Field(description="settling band half-width, channel unit")
    noise: float = Field(
        description="standard deviation of the sample-to-sample noise, channel unit"
    )
    step_found: bool = Field(
        description="a step stands out of the noise (10 σ) and stays: overshoot and rise "
        "time are defined"
    )


class ParamCompare(BaseModel):
    """A parameter as it was at each trace's capture (its default where the capture's
    snapshot did not list it); null only for an import, which has no snapshot."""

    scope: str
    target: str
    name: str
    a: float | int | str | None
    b: float | int | str | None


class TraceCompare(BaseModel):
    """Two traces side by side: which parameters differ, which channels they share."""

    a: TraceInfo
    b: TraceInfo
    params: list[ParamCompare]
    common_channels: list[str]


class ScopeStatus(BaseModel):
    state: Literal["idle", "roll", "armed", "triggered", "done"]
    setup: ScopeSetupModel | None
    cycle: int = Field(description="the machine's newest cycle")
    length_cycles: int
    pre_cycles: int
    filled_cycles: int = Field(description="history the scope holds (≤ record length)")
    trigger_cycle: int | None
    captures: list[TraceInfo] = Field(description="recent captures, newest first")
    recording: RecordingInfo | None
    drive_channels: list[ChannelInfo] = Field(
        description="the signals a drive-rate capture can record, every axis' drive"
    )
    armed_by: str | None = Field(
        None, description="who armed it, 'NAME (role)' (null while idle): it is theirs"
    )
    armed_unix: float | None = Field(None, description="when they armed it")


class RecordingStart(BaseModel):
    """Continuous recording of signals, every cycle, to a Rerun .rrd file."""

    signals: list[str] = Field(min_length=1, max_length=MAX_CHANNELS)


class RecordingInfo(BaseModel):
    id: str
    machine: str
    signals: list[str]
    active: bool
    first_cycle: int
    cycles: int = Field(description="cycles written so far")
    bytes: int = Field(description="size of the .rrd file so far")
    skipped_cycles: int = Field(
        description="cycles lost because writing fell more than the service's ring behind"
    )
    started_unix: float
    stopped_reason: str = Field(
        "",
        description="why it ended ('' while it runs): stopped on request, power cycle, "
        "machine deleted, writing failed, or the recordings' disk quota used up",
    )


ScopeStatus.model_rebuild()
