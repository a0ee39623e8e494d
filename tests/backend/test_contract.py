"""The API contract names what the NC knows: HLI control units in commands."""

from __future__ import annotations

import dataclasses
from typing import Any, get_args

from api.commands import HliUnit
from nc_sim.hli import AXIS_UNITS, CHANNEL_UNITS


def test_hli_units_of_the_contract_are_the_machines() -> None:
    # override has its own command in percent; every other unit the machine accepts is listed
    assert set(get_args(HliUnit)) == (set(AXIS_UNITS) | set(CHANNEL_UNITS)) - {"override"}


def test_every_fault_of_the_catalogue_has_its_model_and_round_trips() -> None:
    """An instructor can inject every fault nc_sim knows, and reads back what was injected."""
    from backend.services.training import to_fault, to_model
    from nc_sim.faults import CATALOGUE

    samples: dict[str, Any] = {"axis": "X", "factor": 1.5, "rms": 0.01, "gear": 2, "v_loss": 0.5}
    samples |= {"width": 0.02, "delay_s": 3.0, "a_max": 2000.0, "seed": 7}
    softer = {"coupling_soft": {"factor": 0.5}}  # a coupling only ever goes soft
    for cls in CATALOGUE:
        own = samples | softer.get(cls.kind, {})
        fields = {f.name: own[f.name] for f in dataclasses.fields(cls)}
        fault = cls(**fields)
        assert to_fault(to_model(fault)) == fault


def test_every_fault_kind_has_the_instructors_words_in_the_schema() -> None:
    """The console's fault form names each kind by its schema title ("Motor wired inverted"),
    not by a class or kind identifier."""
    from api.faults import FaultInject

    defs = FaultInject.model_json_schema()["$defs"]
    kinds = [d for d in defs.values() if "kind" in d.get("properties", {})]
    assert len(kinds) >= 12
    for d in kinds:
        kind = d["properties"]["kind"]["const"]
        title = d["title"]
        assert not title.endswith("Model") and "_" not in title, (kind, title)
        assert title[0].isupper(), title
    titles = [d["title"] for d in kinds]
    assert len(set(titles)) == len(titles)  # told apart in the form
