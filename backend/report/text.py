"""The report's words and numbers: times, values, escaping, tables, assistant titles."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from html import escape

from nc_sim.assist.registry import BY_NAME


def when(t: float) -> str:
    """A time as the report prints it (UTC, to the second)."""
    return time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(t))


def number(v: object) -> str:
    """A figure or parameter value: numbers to 6 significant digits, the rest as text."""
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f"{v:.6g}" if math.isfinite(v) else str(v)
    return str(v)


def e(v: object) -> str:
    return escape(str(v))


def table(head: Sequence[str], rows: list[str], cls: str = "") -> str:
    th = "".join(f"<th>{e(h)}</th>" for h in head)
    body = "".join(rows)
    return f'<table class="{cls}"><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>'


def assistant_title(name: str) -> str:
    """The manual's name and section of an assistant (one no longer known: its name)."""
    a = BY_NAME.get(name)
    return f"{a.title} [{a.section}]" if a else name
