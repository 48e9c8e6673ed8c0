"""The soft-PLC compiler and the checker stay sets of small modules: one per stage or concern, none over
MAX_MODULE_LINES lines and no class over MAX_CLASS_LINES (docs/architecture.md lists who owns what)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "plc" / "st"
CHECKER = PACKAGE.parent / "checker"
MAX_MODULE_LINES = 400
MAX_CLASS_LINES = 300
MODULES = sorted(PACKAGE.rglob("*.py")) + sorted(CHECKER.rglob("*.py"))


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE.parent)))
def test_module_and_class_sizes(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert text.count("\n") <= MAX_MODULE_LINES, f"{path.name}: {text.count(chr(10))} lines"
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ClassDef):
            size = (node.end_lineno or node.lineno) - node.lineno + 1
            assert size <= MAX_CLASS_LINES, f"{path.name}: class {node.name} has {size} lines"


def test_the_stages_are_separate_modules() -> None:
    names = {p.relative_to(PACKAGE).as_posix() for p in MODULES if p.is_relative_to(PACKAGE)}
    for stage in (
        "parser.py",
        "index.py",
        "typerules.py",
        "literals.py",
        "codegen/expressions.py",
        "codegen/statements.py",
        "codegen/pous.py",
        "codegen/initialisers.py",
        "codegen/configuration.py",
    ):
        assert stage in names
