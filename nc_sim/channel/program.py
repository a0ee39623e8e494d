"""A program's structure: the main program and its local subprograms in one text.

    %L tapered thread        a subprogram (name to the end of the line), ends with M29 or M17
    ...
    %G33                     the main program (any other `%` line names it; optional)
    ...                      ends with M30 or M02

Subprograms may come before or after the main program (000 §2.8.7 defines them first).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from nc_sim.channel.words import ProgramError
from nc_sim.errors import Code

_SUB = re.compile(r"%L(?=\s|\d)", re.IGNORECASE)  # `%L name`, `%L123`; `%linear` is a main program


@dataclass
class Program:
    """`main` and each subprogram as 0-based indexes of `lines`; `defined_at` the `%L` line."""

    lines: list[str]
    main: list[int] = field(default_factory=list)
    subprograms: dict[str, list[int]] = field(default_factory=dict)
    defined_at: dict[str, int] = field(default_factory=dict)


def split_program(text: str) -> Program:
    """Split NC text into main program and subprograms (names upper case, spaces collapsed)."""
    prog = Program(text.splitlines())
    current = prog.main
    for index, raw in enumerate(prog.lines):
        stripped = raw.strip()
        if _SUB.match(stripped):
            name = " ".join(stripped[2:].split(";")[0].split()).upper()
            if not name:
                raise ProgramError(
                    "%L needs a subprogram name", index + 1, 1, Code.PROGRAM_STRUCTURE
                )
            if name in prog.subprograms:
                raise ProgramError(
                    f"subprogram {name} defined twice", index + 1, 1, Code.PROGRAM_STRUCTURE
                )
            current = prog.subprograms[name] = []
            prog.defined_at[name] = index
        elif stripped.startswith("%"):
            current = prog.main
        else:
            current.append(index)
    return prog
