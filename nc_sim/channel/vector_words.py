"""#VECTOR LIMIT, the path's own dynamic limits [002 §2.5.2]:

    #VECTOR LIMIT ON [ACC=<a> DEC=<d> VEL=<v> FEED RAPID]   limits as programmed
    #VECTOR LIMIT ON [ACC VEL]                               the channel list's (P-CHAN-00002,
                                                             P-CHAN-00208, P-CHAN-00090)
    #VECTOR LIMIT ON ALL                                     all three, the list's
    #VECTOR LIMIT OFF [ACC]   #VECTOR LIMIT OFF (ALL)        those named, or all, off again

VEL in mm/min, ACC and DEC in the unit P-CHAN-00351 sets. FEED and RAPID name the blocks the
limits act on (feed blocks G01/G02/G03, rapid traverse G00); without either, both. Modal:
each command changes only the limits it names."""

from __future__ import annotations

from nc_sim.channel import canon
from nc_sim.channel.words import Error

_LIMITS = {"ACC": "acceleration", "DEC": "deceleration", "VEL": "velocity"}
_BLOCKS = ("FEED", "RAPID")


def vector_limit(
    cmd: str,
    body: str | None,
    col: int,
    body_col: int,
    now: canon.VectorLimit | None,
    line: int,
    error: Error,
) -> canon.VectorLimit:
    """The limits in force after this command (`now`: before it, None when none were set)."""
    state = now or canon.VectorLimit(line)
    on = cmd.startswith("VECTOR LIMIT ON")
    if cmd.endswith(" ALL"):
        if body is not None:
            raise error(f"#{cmd} takes no [...]", body_col)
        value: canon.PathLimit = "default" if on else None
        return canon.VectorLimit(line, value, value, value, state.feed, state.rapid)
    if body is None:
        if on:
            raise error("#VECTOR LIMIT ON needs [ACC.. DEC.. VEL..] or ALL", col)
        return canon.VectorLimit(line, feed=state.feed, rapid=state.rapid)
    changes: dict[str, canon.PathLimit] = {}
    blocks: list[str] = []
    for item in body.split():
        key, _, text = item.upper().partition("=")
        if key in _BLOCKS and not text and on:
            blocks.append(key)
            continue
        if key not in _LIMITS:
            raise error(
                f"#VECTOR LIMIT knows ACC, DEC, VEL, FEED and RAPID, not '{item}'", body_col
            )
        if not on:
            if text:
                raise error(f"#VECTOR LIMIT OFF takes {key} without a value", body_col)
            changes[_LIMITS[key]] = None
            continue
        if not text:
            changes[_LIMITS[key]] = "default"
            continue
        try:
            number = float(text)
        except ValueError:
            raise error(f"#VECTOR LIMIT {key}= needs a number, not '{text}'", body_col) from None
        if not number > 0 or number == float("inf"):
            raise error(f"#VECTOR LIMIT {key} must be above 0", body_col)
        changes[_LIMITS[key]] = number
    feed, rapid = ("FEED" in blocks, "RAPID" in blocks) if blocks else (state.feed, state.rapid)
    return canon.VectorLimit(
        line,
        changes.get("velocity", state.velocity),
        changes.get("acceleration", state.acceleration),
        changes.get("deceleration", state.deceleration),
        feed,
        rapid,
    )
