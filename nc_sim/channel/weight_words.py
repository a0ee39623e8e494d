"""G130-G133, the acceleration and ramp time weightings of the path axes [002 §2.5.1]:
`G130 X70 Z50` per axis and `G131 = 50` for every axis (in %), G132/G133 the same for the
ramp times. Each selection starts from 100 %: axes not named are at 100 % again, and 50 %
twice is 50 %. They act on feed blocks (G01/G02/G03) from the block on; a weighting block
moves nothing."""

from __future__ import annotations

from collections.abc import Mapping

from nc_sim.channel import canon
from nc_sim.channel.modal import Modal
from nc_sim.channel.words import Error, Word

KIND_OF = {130: "acceleration", 131: "acceleration", 132: "ramp_time", 133: "ramp_time"}


def weighting(
    line: int,
    g: Mapping[int, Word],
    g_values: list[tuple[int, float, int]],
    addr: Mapping[str, Word],
    axes: tuple[str, ...],
    modal: Modal,
    motion_g: int | None,
    error: Error,
) -> canon.Weighting:
    """The weightings in force after this block (`modal` takes them)."""
    axis_words = [addr[a] for a in axes if a in addr]
    if motion_g is not None:
        raise error("a weighting block moves nothing", g[motion_g].column)
    selections: list[tuple[int, dict[str, float], int]] = []
    for number, value, col in g_values:
        if number not in (131, 133):
            raise error(f"G{number} = is not supported (G131 = or G133 =)", col)
        if value <= 0:
            raise error(f"G{number} weighting must be above 0 %", col)
        selections.append((number, dict.fromkeys(axes, value), col))
    for number in (130, 132):
        if number in g:
            col = g[number].column
            if not axis_words:
                raise error(f"G{number} needs axes with their weighting in %", col)
            for w in axis_words:
                if w.value <= 0:
                    raise error(f"G{number} weighting of {w.letter} must be above 0 %", w.column)
            selections.append((number, {w.letter: w.value for w in axis_words}, col))
    if axis_words and not g.keys() & {130, 132}:
        raise error("a weighting block moves nothing", axis_words[0].column)
    chosen: dict[str, dict[str, float]] = {}
    for number, weights, col in selections:
        kind = KIND_OF[number]
        if kind in chosen:
            raise error(f"two {kind.replace('_', ' ')} weightings in one block", col)
        chosen[kind] = weights
    if "acceleration" in chosen:
        modal.acceleration_weight = chosen["acceleration"]
    if "ramp_time" in chosen:
        modal.ramp_time_weight = chosen["ramp_time"]
    return canon.Weighting(
        line, tuple(modal.acceleration_weight.items()), tuple(modal.ramp_time_weight.items())
    )
