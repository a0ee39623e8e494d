"""CSV export and import of traces, exact to the last bit.

One row per cycle: `cycle`, `t_s` (from the trigger), then one column per channel headed
`<axis>.<signal> [unit]`. Numbers are written in Python's shortest round-trip form, so reading
them back gives the same float64 values. A `# meta:` comment line carries the trace's
description as JSON; a CSV without it (from a spreadsheet or another scope) is read from its
header and its `cycle` or `t_s` column.
"""

from __future__ import annotations

import csv
import io
import re
import time
import uuid

import numpy as np
from pydantic import ValidationError

from api.scope import ChannelInfo, TraceDetail
from backend.errors import ApiError
from backend.services.traces import Trace

_HEAD = re.compile(r"^(?P<name>.+?)(?: \[(?P<unit>[^\]]*)\])?$")


def to_csv(trace: Trace) -> str:
    """The trace as CSV text."""
    d = trace.detail
    out = io.StringIO()
    out.write("# inbetrieb trace\n")
    out.write("# meta: " + d.model_dump_json() + "\n")
    heads = [f"{c.name} [{c.unit}]" if c.unit else c.name for c in d.channels]
    out.write(",".join(["cycle", "t_s", *heads]) + "\n")
    cycles = range(d.first_cycle, d.first_cycle + d.count)
    cols = [trace.times_s().tolist(), *(row.tolist() for row in trace.data)]
    for c, values in zip(cycles, zip(*cols, strict=True), strict=True):
        out.write(f"{c}," + ",".join(map(repr, values)) + "\n")
    return out.getvalue()


def _bad(message: str) -> ApiError:
    return ApiError(422, {"message": f"CSV import: {message}"})


def from_csv(text: str, name: str = "") -> Trace:
    """A new trace (own id, source `import`) from CSV text; 422 naming the problem."""
    meta: TraceDetail | None = None
    body: list[str] = []
    for line in text.splitlines():
        if line.startswith("# meta: "):
            try:
                meta = TraceDetail.model_validate_json(line[len("# meta: ") :])
            except ValidationError as e:
                why = e.errors()[0]["msg"]
                raise _bad(f"the # meta line is not a trace description: {why}") from None
        elif not line.startswith("#") and line.strip():
            body.append(line)
    rows = list(csv.reader(body))
    if len(rows) < 3:
        raise _bad("needs a header row and at least two data rows")
    header = [h.strip() for h in rows[0]]
    ragged = next((i for i, r in enumerate(rows) if len(r) != len(header)), None)
    if ragged is not None:
        raise _bad(f"data row {ragged} has {len(rows[ragged])} columns, the header {len(header)}")
    try:
        values = np.array([[float(v) for v in r] for r in rows[1:]])
    except ValueError as e:
        raise _bad(f"not a number: {e}") from None
    cols = {h: i for i, h in enumerate(header)}
    data_idx = [i for i, h in enumerate(header) if h not in ("cycle", "t_s")]
    if not data_idx:
        raise _bad("no data columns besides cycle and t_s")
    if "cycle" in cols:
        cycles = values[:, cols["cycle"]].astype(np.int64)
    else:
        cycles = np.arange(values.shape[0], dtype=np.int64)
    if np.any(np.diff(cycles) != 1):
        raise _bad("rows must be consecutive cycles")
    data = np.ascontiguousarray(values[:, data_idx].T)
    if meta is not None:
        detail = meta.model_copy(deep=True)
        if [c.name for c in detail.channels] != [_split(header[i])[0] for i in data_idx]:
            raise _bad("the columns do not match the # meta line")
    else:
        detail = _detail_from_columns(header, data_idx, values, cols, cycles)
    detail.id = uuid.uuid4().hex[:12]
    detail.source, detail.stored = "import", False
    detail.created_unix = time.time()
    detail.first_cycle, detail.count = int(cycles[0]), int(cycles.size)
    detail.name = name or detail.name or "imported trace"
    return Trace(detail, data)


def _split(head: str) -> tuple[str, str]:
    m = _HEAD.match(head)
    assert m is not None
    return m["name"], m["unit"] or ""


def _detail_from_columns(
    header: list[str],
    data_idx: list[int],
    values: np.ndarray,
    cols: dict[str, int],
    cycles: np.ndarray,
) -> TraceDetail:
    cycle_s, trigger = 0.001, None
    if "t_s" in cols:
        t = values[:, cols["t_s"]]
        cycle_s = float(np.median(np.diff(t)))
        if cycle_s <= 0:
            raise _bad("t_s must increase")
        zero = np.flatnonzero(np.abs(t) < cycle_s / 2)
        trigger = int(cycles[zero[0]]) if zero.size else None
    channels = []
    for i in data_idx:
        n, u = _split(header[i])
        channels.append(ChannelInfo(name=n, unit=u, kind="float"))
    return TraceDetail(
        id="",
        machine="imported",
        machine_name="imported",
        name="",
        notes="",
        source="import",
        stored=False,
        trigger="imported" if trigger is not None else "",
        forced=False,
        created_unix=0.0,
        first_cycle=int(cycles[0]),
        trigger_cycle=trigger,
        count=int(cycles.size),
        cycle_s=cycle_s,
        channels=channels,
        params_changed=0,
        params=[],
        events=[],
    )
