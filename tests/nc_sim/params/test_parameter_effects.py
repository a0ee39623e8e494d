"""Every registered parameter acts, and a behaviour test shows it, or the registry says why
the simulation accepts it without effect (issue 36, item 12): the parameter editor shows that
reason. A test shows a parameter when it names it (its ID or list name) outside the list
parsing tests."""

from __future__ import annotations

import re
from pathlib import Path

from nc_sim.params.definitions import DEFINITIONS
from nc_sim.params.registry import ParamDef

TESTS = Path(__file__).resolve().parents[2]
PARSING = Path(__file__).resolve().parent  # tests/nc_sim/params: list syntax, not behaviour


def _test_text() -> str:
    files = [p for p in TESTS.rglob("*.py") if PARSING not in p.parents]
    return "\n".join(p.read_text(encoding="utf-8") for p in files)


def _named(d: ParamDef, text: str) -> bool:
    index = r"\[\d+\]"
    pattern = re.escape(d.name).replace(r"\[i\]", index).replace(r"\[j\]", index)
    bare = d.name.replace("[i]", "").replace("[j]", "")
    return d.id in text or re.search(pattern, text) is not None or f'"{bare}"' in text


def test_every_parameter_has_a_behaviour_test_or_says_why_it_has_no_effect() -> None:
    text = _test_text()
    lacking = [
        f"{d.id} {d.name}" for d in DEFINITIONS if not d.without_effect and not _named(d, text)
    ]
    assert not lacking, "no behaviour test and no without_effect reason: " + ", ".join(lacking)


def test_a_parameter_without_effect_says_why_in_a_sentence() -> None:
    for d in DEFINITIONS:
        if d.without_effect:
            assert len(d.without_effect.split()) >= 5, d.id
