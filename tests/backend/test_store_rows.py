"""Rows of the store are read by column name: outside `backend/services/store.py` no service
picks a column of a query's row by its position (`row[2]`, `rows[0][0]`, `r[:9]`) or unpacks
a row into names (`user, role = rows[0]`), so a column added or reordered in a SELECT never
shifts what a service reads."""

from __future__ import annotations

import ast
from pathlib import Path

from backend.services.store import Store

SERVICES = Path(__file__).resolve().parents[2] / "backend" / "services"
ROWS, ROW = "rows", "row"
# what these calls give: the rows of a query (a cursor iterates over them) or one row
SOURCES = {"query": ROWS, "fetchall": ROWS, "execute": ROWS, "fetchone": ROW}
NAMED = {"rows": ROWS, "row": ROW, "r": ROW}  # the names rows go by when passed around
KEEP_ROWS = {"reversed", "sorted", "list"}  # their result holds the same rows


def _position(node: ast.expr) -> bool:
    """An index or slice of integer literals: `[2]`, `[-1]`, `[:9]`, `[2:10]`."""
    if isinstance(node, ast.Slice):
        bounds = [b for b in (node.lower, node.upper, node.step) if b is not None]
        return all(_position(b) for b in bounds)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    return isinstance(node, ast.Constant) and type(node.value) is int


def _kind(node: ast.expr, bound: dict[str, str | None]) -> str | None:
    """ROWS, ROW or None: what the expression holds."""
    if isinstance(node, ast.Call):
        f = node.func
        if isinstance(f, ast.Attribute):
            return SOURCES.get(f.attr)
        if isinstance(f, ast.Name) and f.id in KEEP_ROWS and node.args:
            return ROWS if _kind(node.args[0], bound) == ROWS else None
        return None
    if isinstance(node, ast.Name):
        return bound[node.id] if node.id in bound else NAMED.get(node.id)
    if isinstance(node, ast.Subscript) and _kind(node.value, bound) == ROWS:
        return ROW if _position(node.slice) else None  # rows[0]: the first row
    return None


def _loops(tree: ast.AST) -> list[tuple[ast.expr, ast.expr]]:
    """(target, iterable) of every for loop and comprehension."""
    found: list[tuple[ast.expr, ast.expr]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.For | ast.AsyncFor | ast.comprehension):
            found.append((node.target, node.iter))
    return found


def _row_target(target: ast.expr, it: ast.expr, bound: dict[str, str | None]) -> ast.expr | None:
    """What takes one row each time round a loop: `r` of `for r in rows` and of
    `for i, r in enumerate(rows)`; None for a loop over no rows."""
    if _kind(it, bound) == ROWS:
        return target
    if (
        isinstance(it, ast.Call)
        and isinstance(it.func, ast.Name)
        and it.func.id == "enumerate"
        and it.args
        and _kind(it.args[0], bound) == ROWS
        and isinstance(target, ast.Tuple)
        and len(target.elts) == 2
    ):
        return target.elts[1]
    return None


def _bindings(scope: ast.AST) -> dict[str, str | None]:
    """What each name assigned in a function holds (a row, rows, or neither)."""
    bound: dict[str, str | None] = {}
    for _ in range(2):  # a name bound from one bound before
        for node in ast.walk(scope):
            if isinstance(node, ast.Assign | ast.AnnAssign) and node.value is not None:
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                kind = _kind(node.value, bound)
                if kind is None and isinstance(node.value, ast.Call):
                    continue  # a call of unknown result: the name says (`row = self._row()`)
                for t in targets:
                    if isinstance(t, ast.Name):
                        bound[t.id] = kind
        for target, it in _loops(scope):
            each = _row_target(target, it, bound)
            if isinstance(each, ast.Name):
                bound[each.id] = ROW
    return bound


def positional_row_access(source: str) -> list[int]:
    """Lines that read a store row by position or unpack one."""
    tree = ast.parse(source)
    lines: set[int] = set()
    functions = ast.FunctionDef | ast.AsyncFunctionDef
    for scope in (n for n in ast.walk(tree) if isinstance(n, functions)):
        bound = _bindings(scope)
        for node in ast.walk(scope):
            if isinstance(node, ast.Subscript):
                positional = _position(node.slice)  # row[2], row[:9]
            elif isinstance(node, ast.Assign):
                positional = isinstance(node.targets[0], ast.Tuple)  # a, b = row
            else:
                continue
            if positional and _kind(node.value, bound) == ROW:
                lines.add(node.lineno)
        for target, it in _loops(scope):  # for a, b in rows
            if isinstance(_row_target(target, it, bound), ast.Tuple):
                lines.add(target.lineno)
    return sorted(lines)


OLD = """
def users(self):
    rows = self.store.query("SELECT name, role, created FROM users")
    return [UserEntry(r[0], Role(r[1]), r[2]) for r in rows]

def first_admin(self):
    rows = self.store.query("SELECT name FROM users WHERE role = ?", ("admin",))
    return rows[0][0] if rows else None

def session(self, sid):
    rows = self.store.query("SELECT user, role, csrf FROM sessions WHERE digest = ?", (sid,))
    user, role, csrf = rows[0]

def take(db):
    return db.execute("SELECT count(*) FROM param_versions").fetchone()[0]

def total(self):
    return self.store.query("SELECT count(*) FROM assist_runs")[0][0]

def _info(r):
    return AssistRunInfo(id=r[0], machine=r[1])

def _run(r):
    return _info(r[:9])

def delete(self, mid, vid):
    row = self._row(mid, vid)
    if row[6]:
        raise Conflict(row[2])

def verify(self):
    for i, r in enumerate(self.store.query("SELECT seq FROM audit_log"), start=1):
        if r[0] != i:
            return False

def commissioners(self):
    for user, n in self.store.query("SELECT user, count(*) FROM assist_runs GROUP BY user"):
        pass
"""

NEW = """
def users(self):
    rows = self.store.query("SELECT name, role, created FROM users")
    return [UserEntry(r["name"], Role(r["role"]), r["created"]) for r in rows]

def first_admin(self):
    rows = self.store.query("SELECT name FROM users WHERE role = ?", ("admin",))
    return rows[0]["name"] if rows else None

def tokens(self):
    return [f"token-{r['digest'][:16]}" for r in self.store.query("SELECT digest FROM tokens")]

def add(self, mid, result):
    row = (mid, result.assistant)
    return row[0]

def counts(seen, user, n):
    s = seen.setdefault(user, [0, 0])
    s[0], s[1] = n, s[1] + 1
    first, last = sorted(seen)[0], sorted(seen)[-1]
"""


def test_the_check_finds_positional_reads() -> None:
    assert positional_row_access(OLD) == [4, 8, 12, 15, 18, 21, 24, 28, 29, 33, 37]
    assert positional_row_access(NEW) == []


def test_no_service_reads_a_store_row_by_position() -> None:
    found = {
        p.name: where
        for p in sorted(SERVICES.rglob("*.py"))
        if p.name != "store.py" and (where := positional_row_access(p.read_text()))
    }
    assert found == {}


def test_rows_are_read_by_column_name(tmp_path: Path) -> None:
    store = Store(tmp_path / "store.db")
    try:
        store.run("CREATE TABLE t (a TEXT, b INTEGER)")
        store.run("INSERT INTO t VALUES (?, ?)", ("x", 2))
        (r,) = store.query("SELECT b, a, count(*) AS n FROM t")
        assert (r["a"], r["b"], r["n"]) == ("x", 2, 1)
        assert store.transaction(lambda db: db.execute("SELECT a FROM t").fetchone()["a"]) == "x"
    finally:
        store.close()
