"""Schema violations as sentences an operator can read: the field's meaning and unit from the
API schema, the rule it broke ("must be at most 1000000 mm/min"), never pydantic's
"Input should be …" text."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Any

# unit suffixes of field names (the project names units in field names where ambiguous),
# longest first; a field whose name does not say its unit has it as `x-unit` in its schema
_UNIT_SUFFIX = [
    ("_m_per_min", "m/min"),
    ("_deg_s2", "°/s²"),
    ("_deg_s", "°/s"),
    ("_mm_s", "mm/s"),
    ("_digits", "digits"),
    ("_mm_min", "mm/min"),
    ("_rpm", "rpm"),
    ("_deg", "°"),
    ("_mm", "mm"),
    ("_ms", "ms"),
    ("_s", "s"),
    ("_pct", "%"),
]
_NAMED_UNITS = {"percent": "%"}
_LOC_ROOTS = {"body", "query", "path", "header", "cookie"}


class FieldTexts:
    """Meaning and unit of every request field, from the OpenAPI schema: keyed by (tag,
    field), the tag being the `type` literal of a command union member (None for other
    models)."""

    def __init__(self, openapi: Mapping[str, Any]) -> None:
        # (description, x-unit), "" where the schema has none
        self._by_tag: dict[tuple[str | None, str], tuple[str, str]] = {}
        self._by_model: dict[tuple[str, str], tuple[str, str]] = {}
        self._by_name: dict[str, set[tuple[str, str]]] = {}
        schemas = openapi.get("components", {}).get("schemas", {})
        for model, schema in schemas.items():
            props: Mapping[str, Any] = schema.get("properties", {})
            tag = props.get("type", {}).get("const")
            for name, prop in props.items():
                texts = (_description(prop), _schema_unit(prop))
                if tag is not None:
                    self._by_tag[(tag, name)] = texts
                self._by_model[(model, name)] = texts
                if any(texts):
                    self._by_name.setdefault(name, set()).add(texts)

    def texts(self, tag: str | None, name: str, model: str | None = None) -> tuple[str, str]:
        """The field's description and unit: of the command `tag`, else of the route's body
        `model`, else of the one meaning all models give `name` ("" where the schema has
        none, or where models describe the field differently)."""
        if (tag, name) in self._by_tag:
            return self._by_tag[(tag, name)]
        if model is not None and (model, name) in self._by_model:
            return self._by_model[(model, name)]
        texts = self._by_name.get(name, set())
        return next(iter(texts)) if len(texts) == 1 else ("", "")


def _description(prop: Mapping[str, Any]) -> str:
    if "description" in prop:
        return str(prop["description"])
    for alt in prop.get("anyOf", []):  # Optional[Annotated[...]]: on the non-null member
        if "description" in alt:
            return str(alt["description"])
    return ""


def _schema_unit(prop: Mapping[str, Any]) -> str:
    if "x-unit" in prop:
        return str(prop["x-unit"])
    for alt in prop.get("anyOf", []):  # Optional[...]: on the non-null member
        if unit := _schema_unit(alt):
            return unit
    items = prop.get("items")  # a list of values with a unit (kv values to try)
    return _schema_unit(items) if isinstance(items, Mapping) else ""


def _unit(name: str, schema_unit: str) -> str:
    """The unit its schema names, else the one its name says (feed_mm_min)."""
    if schema_unit:
        return schema_unit
    if name in _NAMED_UNITS:
        return _NAMED_UNITS[name]
    for suffix, unit in _UNIT_SUFFIX:
        if name.endswith(suffix):
            return unit
    return schema_unit


def _meaning(tag: str | None, name: str, description: str, unit: str) -> str:
    if description:
        first = re.split(r"[,;:(]", description, maxsplit=1)[0].strip()
        if first and first != unit:
            return first
    words = name
    for suffix, _ in _UNIT_SUFFIX:
        if words.endswith(suffix):
            words = words[: -len(suffix)]
            break
    words = words.replace("_", " ")
    return f"{tag.replace('_', ' ')} {words}" if tag else words


def _num(x: Any) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _rule(kind: str, ctx: Mapping[str, Any], unit: str, msg: str) -> str:
    u = f" {unit}" if unit else ""
    rules = {
        "less_than_equal": f"must be at most {_num(ctx.get('le'))}{u}",
        "less_than": f"must be less than {_num(ctx.get('lt'))}{u}",
        "greater_than_equal": f"must be at least {_num(ctx.get('ge'))}{u}",
        "greater_than": f"must be greater than {_num(ctx.get('gt'))}{u}",
        "finite_number": "must be a finite number",
        "missing": "is required",
        "literal_error": f"must be one of {ctx.get('expected', '')}",
        "enum": f"must be one of {ctx.get('expected', '')}",
        "string_too_long": f"must be at most {ctx.get('max_length')} characters",
        "string_too_short": f"must be at least {ctx.get('min_length')} characters",
    }
    if kind in rules:
        return rules[kind]
    if kind.endswith("_parsing") or kind.endswith("_type"):
        return {"int": "must be a whole number", "float": "must be a number"}.get(
            kind.split("_")[0], "has the wrong type"
        )
    return re.sub(r"^Input should", "must", msg) or "is not valid"


def issue_text(
    fields: FieldTexts,
    loc: Sequence[str | int],
    kind: str,
    ctx: Mapping[str, Any],
    msg: str,
    model: str | None = None,
) -> str:
    """One schema violation as a sentence, e.g. "Jog feed must be greater than 0 mm/min";
    `model` names the route's body model (its schema component)."""
    names = [p for p in loc if isinstance(p, str) and p not in _LOC_ROOTS]
    if not names:
        return f"The request {_rule(kind, ctx, '', msg)}."
    name = names[-1]
    tag = names[-2] if len(names) > 1 else None
    description, schema_unit = fields.texts(tag, name, model if len(names) == 1 else None)
    unit = _unit(name, schema_unit)
    meaning = _meaning(tag, name, description, unit)
    text = f"{meaning} {_rule(kind, ctx, unit, msg)}"
    return text[0].upper() + text[1:] + "."
