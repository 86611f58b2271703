"""Complexity guard: no function in ``desmon/`` is above cyclomatic complexity
20 or longer than 80 lines unless its docstring says why, on a line of its own::

    Complexity: one branch per keyword of the DSL; splitting it would scatter the table.

Complexity is radon's (``radon cc -s desmon`` prints the same numbers); length is the
whole ``def`` from its first line to its last, docstring included, decorators not.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import pytest

radon_complexity = pytest.importorskip("radon.complexity")

PACKAGE = Path(__file__).resolve().parent.parent / "desmon"
MAX_COMPLEXITY = 20
MAX_LINES = 80
#: explained exceptions allowed in the whole package: the escape hatch is for the rare
#: flat dispatch that reads best in one piece, not a way around the limits
MAX_EXPLAINED = 6
#: words a reason needs at least (a reason says why splitting would hurt, not "long")
MIN_REASON_WORDS = 5
MARK = "Complexity:"


@dataclass(frozen=True, slots=True)
class FunctionFacts:
    path: str
    line: int
    name: str
    complexity: int
    lines: int
    reason: str | None

    @property
    def over(self) -> bool:
        return self.complexity > MAX_COMPLEXITY or self.lines > MAX_LINES

    def describe(self) -> str:
        return f"{self.path}:{self.line} {self.name} cc={self.complexity} lines={self.lines}"


def _radon_complexities(source: str) -> dict[tuple[int, int], int]:
    """(line, column) of each def -> radon's cyclomatic complexity, nested ones included."""
    out: dict[tuple[int, int], int] = {}

    def walk(blocks: list) -> None:
        for b in blocks:
            if hasattr(b, "methods"):  # a class
                walk(b.methods)
                walk(b.inner_classes)
            else:
                out[(b.lineno, b.col_offset)] = b.complexity
                walk(b.closures)

    walk(radon_complexity.cc_visit(source))
    return out


def _alone(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Radon's complexity of one def it does not list itself (a method of a class defined in a function)."""
    return radon_complexity.cc_visit_ast(ast.Module(body=[node], type_ignores=[]))[0].complexity


def _reason(node: ast.FunctionDef | ast.AsyncFunctionDef) -> str | None:
    """The text after ``Complexity:`` on a docstring line of its own ('' if empty), or None."""
    doc = ast.get_docstring(node) or ""
    for line in doc.splitlines():
        line = line.strip()
        if line.startswith(MARK):
            return line[len(MARK):].strip()
    return None


def scan(path: str, source: str) -> Iterator[FunctionFacts]:
    """Every function and method of ``source`` with its complexity, length and reason."""
    complexities = _radon_complexities(source)

    def visit(node: ast.AST, prefix: str) -> Iterator[FunctionFacts]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + child.name
                yield FunctionFacts(
                    path,
                    child.lineno,
                    name,
                    complexities.get((child.lineno, child.col_offset)) or _alone(child),
                    child.end_lineno - child.lineno + 1,  # type: ignore[operator]  # always set by the parser
                    _reason(child),
                )
                yield from visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                yield from visit(child, prefix + child.name + ".")
            else:
                yield from visit(child, prefix)

    yield from visit(ast.parse(source), "")


def package_functions() -> list[FunctionFacts]:
    out: list[FunctionFacts] = []
    for file in sorted(PACKAGE.rglob("*.py")):
        rel = file.relative_to(PACKAGE.parent).as_posix()
        out.extend(scan(rel, file.read_text(encoding="utf-8")))
    return out


@pytest.fixture(scope="module")
def functions() -> list[FunctionFacts]:
    return package_functions()


def test_no_function_is_too_complex_or_too_long_without_a_reason(functions: list[FunctionFacts]) -> None:
    offenders = [f for f in functions if f.over and not f.reason]
    assert not offenders, (
        f"{len(offenders)} function(s) above cyclomatic complexity {MAX_COMPLEXITY} or {MAX_LINES} lines: "
        f"split them, or say why not on a docstring line '{MARK} <reason>':\n"
        + "\n".join(f.describe() for f in offenders)
    )


def test_explained_exceptions_are_few_and_say_why(functions: list[FunctionFacts]) -> None:
    explained = [f for f in functions if f.over and f.reason is not None]
    thin = [f for f in explained if len(f.reason.split()) < MIN_REASON_WORDS]  # type: ignore[union-attr]
    assert not thin, f"'{MARK}' reasons under {MIN_REASON_WORDS} words:\n" + "\n".join(
        f"{f.describe()} reason={f.reason!r}" for f in thin
    )
    assert len(explained) <= MAX_EXPLAINED, (
        f"{len(explained)} functions over the limits excuse themselves with '{MARK}' (at most {MAX_EXPLAINED}): "
        "split some of them:\n" + "\n".join(f.describe() for f in explained)
    )


def test_a_reason_on_a_function_within_the_limits_is_reported_as_stale(functions: list[FunctionFacts]) -> None:
    stale = [f for f in functions if f.reason is not None and not f.over]
    assert not stale, f"'{MARK}' lines on functions now within the limits: delete them:\n" + "\n".join(
        f.describe() for f in stale
    )


_SYNTHETIC = '''
class Table:
    def dispatch(self, key):
        """Route a key.{reason}"""
{branches}
        return None


def short():
    return 1
'''


def _synthetic(reason: str, branches: int) -> list[FunctionFacts]:
    body = "\n".join(f"        if key == {i}:\n            return {i}" for i in range(branches))
    return list(scan("x.py", _SYNTHETIC.format(reason=reason, branches=body)))


def test_the_guard_measures_complexity_length_and_reason_of_each_method() -> None:
    dispatch, short = _synthetic("", 25)
    assert (dispatch.name, dispatch.line, dispatch.complexity, dispatch.reason) == ("Table.dispatch", 3, 26, None)
    assert dispatch.lines == 2 + 2 * 25 + 1 and dispatch.over
    assert (short.name, short.complexity, short.lines, short.over) == ("short", 1, 2, False)
    assert dispatch.describe() == "x.py:3 Table.dispatch cc=26 lines=53"
    explained, _ = _synthetic("\n\n        Complexity: one branch per key, a flat table reads best whole.\n        ", 25)
    assert explained.reason == "one branch per key, a flat table reads best whole."
    empty, _ = _synthetic("\n\n        Complexity:\n        ", 25)
    assert empty.reason == ""
