"""NC programs: stored by name (service-wide, or a class seat's own), and a program's commanded
tool path to preview."""

from __future__ import annotations

from datetime import datetime
from typing import Literal

from pydantic import BaseModel, Field

from api.commands import PROGRAM_MAX_CHARS, ProgramName


class ProgramText(BaseModel):
    """A program's text (DIN 66025), for `PUT /api/programs/{name}` and the preview."""

    text: str = Field(max_length=PROGRAM_MAX_CHARS, description="the program, lines of NC blocks")


class ProgramInfo(BaseModel):
    """A stored program as the list shows it."""

    name: ProgramName
    size: int = Field(description="characters")
    lines: int
    updated_at: datetime = Field(description="when it was last written, UTC")
    updated_by: str = Field(description="who wrote it last")
    seat: str | None = Field(
        None, description="a class seat's own program (that seat's machine); null: service-wide"
    )


class Program(ProgramInfo):
    """A stored program with its text."""

    text: str


class PreviewError(BaseModel):
    """Where the program stops interpreting: the first error, 1-based line and column."""

    line: int
    column: int
    code: int = Field(description="job error number (e.g. 90010 block syntax)")
    message: str


class PreviewSegment(BaseModel):
    """One motion of the program as a polyline in the preview's plane."""

    line: int = Field(description="1-based line of the block that commands it")
    rapid: bool = Field(description="G00 (drawn dashed); else G01/G02/G03 at the feed")
    points: list[tuple[float, float]] = Field(
        description="(horizontal, vertical) positions in mm along the path, its start first; "
        "arcs in chords within 1 µm of the arc (at most 2000 points per arc)"
    )


class ProgramPreview(BaseModel):
    """The commanded tool path of a program from the machine's commanded position, up to its
    first error (the calls before it are drawn)."""

    error: PreviewError | None
    plane: Literal["G17", "G18", "G19"] = Field(
        description="the plane drawn: the first the program selects, else the machine's "
        "natural one (G17 with X and Y, G18 on a lathe)"
    )
    axes: tuple[str, str] = Field(
        description="the plane's axes (horizontal, vertical): G17 X,Y; G18 Z,X; G19 Y,Z"
    )
    segments: list[PreviewSegment]
    truncated: bool = Field(
        False, description="the program has more points than a preview draws: the rest is left out"
    )
