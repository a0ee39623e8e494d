"""One error table: `backend/errors.py` is the only place in the service that names an HTTP
status; everything else raises an error class (or names a constant of that module)."""

from __future__ import annotations

import ast
from collections.abc import Sequence
from pathlib import Path

from backend import errors
from backend.errors import STATUS, WORKER_FAILURE, ApiError, http_status

BACKEND = Path(__file__).resolve().parents[2] / "backend"
STATUS_NAMES = {"status", "status_code"}
ANSWERS = {"ApiError", "HTTPException", "JSONResponse", "Response", "HTMLResponse"}
ANSWERS |= {"RedirectResponse", "PlainTextResponse", "StreamingResponse", "responses"}


def _status(node: ast.AST) -> bool:
    """A literal that reads as an HTTP status (or a tuple, list or set of them)."""
    if isinstance(node, ast.Constant):
        return type(node.value) is int and 100 <= node.value <= 599
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_status(e) for e in node.elts)
    return False


def _error_statuses(values: Sequence[object]) -> bool:
    return all(type(v) is int and 400 <= v <= 599 for v in values)


def _names_status(node: ast.AST) -> bool:
    if isinstance(node, ast.Attribute):
        return node.attr in STATUS_NAMES
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
        return node.slice.value in STATUS_NAMES
    return isinstance(node, ast.Name) and node.id in STATUS_NAMES


def _callee(call: ast.Call) -> str:
    f = call.func
    return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""


def literal_statuses(source: str) -> list[int]:
    """Lines where a literal HTTP status is given, compared or mapped."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.keyword) and node.arg in STATUS_NAMES and _status(node.value):
            lines.append(node.value.lineno)
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_names_status(s) for s in sides) and any(_status(s) for s in sides):
                lines.append(node.lineno)
        elif isinstance(node, ast.Call) and _callee(node) in ANSWERS:
            lines += [a.lineno for a in node.args if _status(a)]
        elif isinstance(node, ast.Dict):  # statuses mapped to reasons, or kinds to statuses
            lines += [k.lineno for k in node.keys if k is not None and _status(k)]
            values = [v.value for v in node.values if isinstance(v, ast.Constant)]
            if values and len(values) == len(node.values) and _error_statuses(values):
                lines.append(node.lineno)
        elif (
            isinstance(node, ast.Return | ast.Assign)
            and isinstance(node.value, ast.Tuple)
            and node.value.elts
            and _status(node.value.elts[0])  # (status, why)
        ):
            lines.append(node.lineno)
    return sorted(lines)


def test_no_status_is_named_outside_the_error_table() -> None:
    found = {
        str(p.relative_to(BACKEND.parent)): where
        for p in sorted(BACKEND.rglob("*.py"))
        if p.name != "errors.py" and (where := literal_statuses(p.read_text()))
    }
    assert found == {}


def test_the_check_finds_each_way_a_status_was_written() -> None:
    """The forms the service used before the table (each must be caught)."""
    samples = [
        "raise ApiError(409, {'message': 'x'})",
        "@router.post('/x', status_code=201)\ndef f(): ...",
        "r = responses(403, 404, why={409: 'taken'})",
        "if e.status == 503: pass",
        "code = {'not_found': 404}.get(kind, 500)",
        "def f():\n    return 401, 'not logged in'",
        "ok = start['status'] in (413, 431)",
        "BINARY = {200: {'content': {}}}",
    ]
    assert [bool(literal_statuses(s)) for s in samples] == [True] * len(samples)
    assert literal_statuses("x = text[:500]\nlimit = Query(le=200)\nn = 404 + 1") == []


def test_each_error_class_has_one_status_and_a_built_in_base() -> None:
    codes = [code for code, _ in STATUS.values()]
    assert len(codes) == len(set(codes))  # one class per status
    for kind in STATUS:
        assert issubclass(kind, ApiError)
        assert kind.__mro__[2] is not Exception  # our class, then a built-in it refines
    assert http_status(errors.NotFound) == 404 and errors.NotFound("x").status == 404
    assert {http_status(kind) for kind in WORKER_FAILURE.values()} == {404, 422, 409, 500}


def test_a_class_derived_from_a_table_class_answers_its_status() -> None:
    class NoSuchSpindle(errors.NotFound):
        pass

    e = NoSuchSpindle("spindle S3")
    assert (e.status, e.detail, str(e)) == (404, {"message": "spindle S3"}, "spindle S3")
    assert isinstance(e, LookupError)
