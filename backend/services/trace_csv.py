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
from array import array
from collections.abc import Iterator

import numpy as np
from pydantic import ValidationError

from api.scope import ChannelInfo, TraceDetail
from backend.errors import ApiError, Invalid, clip
from backend.services.traces import Trace

_HEAD = re.compile(r"^(?P<name>.+?)(?: \[(?P<unit>[^\]]*)\])?$")
MAX_VALUES = 8_000_000  # 64 MB of samples, e.g. 16 channels of 500 000 cycles
MAX_CYCLE = 2**53  # exact in float64, where the CSV's numbers pass through


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
    return Invalid(f"CSV import: {message}")


def from_csv(text: str, name: str = "") -> Trace:
    """A new trace (own id, source `import`) from CSV text; 422 naming the problem.

    Rows are parsed one by one into one array of float64 (8 bytes a value beside the text),
    and every value must be a finite number: what is stored can always be listed again.
    """
    metas: list[str] = []
    reader = csv.reader(_body_lines(text, metas))
    try:
        header = [h.strip() for h in next(reader, [])]
        values = _values(reader, header)
    except csv.Error as e:  # e.g. a field beyond the csv module's field size limit
        raise _bad(f"line {reader.line_num}: {e}") from None
    meta = _meta(metas[-1]) if metas else None
    if values.shape[0] < 2:
        raise _bad("needs a header row and at least two data rows")
    cols = {h: i for i, h in enumerate(header)}
    data_idx = [i for i, h in enumerate(header) if h not in ("cycle", "t_s")]
    if not data_idx:
        raise _bad("no data columns besides cycle and t_s")
    names = [_split(header[i], i)[0] for i in data_idx]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise _bad(f"column names must be unique: {', '.join(twice)}")
    cycles = _cycles(values[:, cols["cycle"]] if "cycle" in cols else None, values.shape[0])
    data = np.ascontiguousarray(values[:, data_idx].T)
    if meta is not None:
        detail = meta.model_copy(deep=True)
        if [c.name for c in detail.channels] != names:
            raise _bad("the columns do not match the # meta line")
    else:
        detail = _detail_from_columns(header, data_idx, values, cols, cycles)
    detail.id = uuid.uuid4().hex[:12]
    detail.source, detail.stored = "import", False
    detail.created_unix = time.time()
    detail.first_cycle, detail.count = int(cycles[0]), int(cycles.size)
    detail.name = name or detail.name or "imported trace"
    return Trace(detail, data)


def _body_lines(text: str, metas: list[str]) -> Iterator[str]:
    """The header and data lines (comment and blank lines skipped, `# meta:` kept aside)."""
    for line in io.StringIO(text):
        if line.startswith("# meta: "):
            metas.append(line[len("# meta: ") :])
        elif not line.startswith("#") and line.strip():
            yield line


def _meta(line: str) -> TraceDetail:
    try:
        meta = TraceDetail.model_validate_json(line)
    except ValidationError as e:
        why = e.errors()[0]["msg"]
        raise _bad(f"the # meta line is not a trace description: {why}") from None
    if not meta.cycle_s > 0:
        raise _bad(f"the # meta line: cycle_s must be > 0, not {meta.cycle_s:g}")
    return meta


def _values(reader: Iterator[list[str]], header: list[str]) -> np.ndarray:
    """The data rows as rows × columns float64; every value a finite number."""
    width = len(header)
    flat = array("d")
    rows = 0
    for rows, row in enumerate(reader, start=1):
        if len(row) != width:
            raise _bad(f"data row {rows} has {len(row)} columns, the header {width}")
        if len(flat) + width > MAX_VALUES:
            raise _bad(f"more than {MAX_VALUES} values")
        try:
            flat.extend(map(float, row))
        except ValueError:
            col = next(k for k, v in enumerate(row) if not _is_number(v))
            raise _bad(
                f"data row {rows}, column {col + 1} ({clip(header[col], 40)}): "
                f"{clip(row[col].strip(), 40)!r} is not a number"
            ) from None
    values = np.frombuffer(flat, dtype=np.float64).reshape(rows, width)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, c = (int(x) for x in bad[0])
        raise _bad(
            f"data row {r + 1}, column {c + 1} ({clip(header[c], 40)}): "
            f"{values[r, c]} is not a finite number"
        )
    return values


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _cycles(column: np.ndarray | None, rows: int) -> np.ndarray:
    """The cycle numbers: whole, consecutive, within what a cycle counter holds."""
    if column is None:
        return np.arange(rows, dtype=np.int64)
    if np.any(np.abs(column) > MAX_CYCLE) or np.any(column != np.round(column)):
        raise _bad(f"cycle must hold whole numbers up to {MAX_CYCLE}")
    cycles = column.astype(np.int64)
    if np.any(np.diff(cycles) != 1):
        raise _bad("rows must be consecutive cycles")
    return cycles


def _split(head: str, col: int) -> tuple[str, str]:
    """Name and unit of a column headed `name [unit]`; 422 when it has no name."""
    m = _HEAD.match(head)
    if m is None or not m["name"].strip():
        raise _bad(f"column {col + 1} has no name")
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
        if not cycle_s > 0:
            raise _bad("t_s must increase")
        zero = np.flatnonzero(np.abs(t) < cycle_s / 2)
        trigger = int(cycles[zero[0]]) if zero.size else None
    channels = []
    for i in data_idx:
        n, u = _split(header[i], i)
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
