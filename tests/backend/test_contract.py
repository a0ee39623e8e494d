"""The API contract names what the NC knows: HLI control units in commands."""

from __future__ import annotations

from typing import get_args

from api.commands import HliUnit
from nc_sim.hli import AXIS_UNITS, CHANNEL_UNITS


def test_hli_units_of_the_contract_are_the_machines() -> None:
    # override has its own command in percent; every other unit the machine accepts is listed
    assert set(get_args(HliUnit)) == (set(AXIS_UNITS) | set(CHANNEL_UNITS)) - {"override"}
