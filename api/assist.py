"""Commissioning assistants [004 §3.4-§3.6, 000 §2.2.4, §2.8.4]: what to run, and what they
answer. Each assistant's request model is made from its descriptor (nc_sim/assist/registry.py):
its inputs with their ranges, units and defaults."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, create_model, field_validator, model_validator

from api.commands import AxisName
from api.common import unit
from nc_sim.assist.descriptor import (
    REQUIRED,
    Assistant,
    AxisChoice,
    Choice,
    Flag,
    Input,
    Kind,
    Number,
    NumberList,
    Table,
)
from nc_sim.assist.registry import ASSISTANTS


def _bounds(n: Number) -> dict[str, Any]:
    out: dict[str, Any] = {"description": n.text}
    if n.lo is not None:
        out["gt" if n.lo_open else "ge"] = int(n.lo) if n.integer else n.lo
    if n.hi is not None:
        out["le"] = int(n.hi) if n.integer else n.hi
    if n.unit:
        out["json_schema_extra"] = unit(n.unit)
    return out


def _number(n: Number) -> Any:
    return Annotated[int if n.integer else float, Field(**_bounds(n))]


def _field(i: Input) -> tuple[Any, Any]:
    """(type, default) of one input as pydantic takes it."""
    default: Any = ... if i.default is REQUIRED else i.default
    bounds: dict[str, Any]
    match i:
        case Number():
            t: Any = _number(i)
            bounds = {}
        case Choice():
            t = Literal[tuple(o for o, _ in i.options)]
            meaning = ", ".join(f"{o} {text}" for o, text in i.options)
            # the HMI's options, and its label without the codes the description lists
            labels = {"x-labels": {str(o): text for o, text in i.options}, "x-title": i.text}
            bounds = {"description": f"{i.text}: {meaning}", "json_schema_extra": labels}
        case Flag():
            t, bounds = bool, {"description": i.text}
        case AxisChoice():  # the HMI offers the machine's axes of these kinds
            kinds = {"x-axis-kinds": list(i.kinds)}
            t, bounds = AxisName, {"description": i.text, "json_schema_extra": kinds}
        case NumberList():
            t = list[_number(i.item)]  # type: ignore[misc]
            bounds = {"min_length": i.min_len, "max_length": i.max_len, "description": i.text}
        case Table():
            columns: dict[str, Any] = {c.name: (_number(c), ...) for c in i.columns}
            row = create_model(i.row, **columns)
            t = list[row]
            bounds = {"min_length": i.min_len, "max_length": i.max_len, "description": i.text}
    if i.optional:
        t = t | None
    return t, Field(default, **bounds)


def request_model(a: Assistant) -> type[BaseModel]:
    """The API model of assistant `a`'s inputs (named as the descriptor says)."""
    fields: dict[str, Any] = {i.name: _field(i) for i in a.inputs}
    doc = f"{a.title} ({a.section}): {a.text}"
    # an input the assistant does not have is refused, not dropped: a misspelt one would
    # otherwise run it with its default (and a live one moves the machine)
    config = ConfigDict(extra="forbid", allow_inf_nan=False)
    return create_model(a.request, __doc__=doc, __config__=config, **fields)


REQUESTS: dict[str, type[BaseModel]] = {a.name: request_model(a) for a in ASSISTANTS}
"""Every assistant's request model, by the assistant's name."""


class AssistantInfo(BaseModel):
    """One assistant as the HMI offers it: its form is made from `request` (a JSON schema)."""

    name: str
    title: str
    section: str = Field(description="the manual's section, e.g. 004 §3.6.2")
    text: str
    kind: Kind = Field(description="calculator: answered at once; experiment: on a copy")
    live: bool = Field(description="may run on the machine itself")
    summary: list[str] = Field(description="the figures that say what a run found")
    request: dict[str, Any] = Field(description="the JSON schema of its inputs")


def catalogue() -> list[AssistantInfo]:
    """Every assistant, in the order the HMI offers them."""
    return [
        AssistantInfo(
            name=a.name,
            title=a.title,
            section=a.section,
            text=a.text,
            kind=a.kind,
            live=bool(a.live),
            summary=list(a.summary),
            request=REQUESTS[a.name].model_json_schema(),
        )
        for a in ASSISTANTS
    ]


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
    run_id: int | None = Field(
        None, description="the stored run this answer is (GET .../assist/runs/{run_id})"
    )


# --- the calculators (004 §3.4, §3.6.1, 000 §2.2.4, §2.8.4) and the gear ranges (000 §2.8.2):
# pure arithmetic on the inputs; the machine only supplies the values "before".

GearStage = Annotated[int, Field(ge=1, le=6, description="gear stage 1-6 (M40-M45, getriebe[0-5])")]


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
