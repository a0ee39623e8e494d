"""Parameter registry and the native parameter list format."""

from nc_sim.params.definitions import registry
from nc_sim.params.listfile import (
    ParamError,
    ParamList,
    ParamListError,
    Value,
    format_list,
    parse_list,
    resolve,
    validate_values,
)
from nc_sim.params.registry import DType, Effect, ParamDef, Registry, Scope

__all__ = [
    "DType",
    "Effect",
    "ParamDef",
    "ParamError",
    "ParamList",
    "ParamListError",
    "Registry",
    "Scope",
    "Value",
    "format_list",
    "parse_list",
    "registry",
    "resolve",
    "validate_values",
]
