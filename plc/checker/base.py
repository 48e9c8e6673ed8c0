"""The checker's per-file state and how a rule reports a finding."""

from __future__ import annotations

from tree_sitter import Node

from plc.checker.lexical import LexicalScan
from plc.st.diagnostics import Diagnostic
from plc.st.index import Index
from plc.st.model import CompileError
from plc.st.parser import ParsedSource
from plc.st.types import UNKNOWN, Type


class CheckerBase:
    """One file under check: its parse, lexical scan, the program's index (the compiler's, built
    leniently from every file of the run), the findings."""

    def __init__(self, ps: ParsedSource, lexical: LexicalScan, index: Index):
        self.ps = ps
        self.lexical = lexical
        self.index = index
        self.diagnostics: list[Diagnostic] = []

    # ---- declarations --------------------------------------------------------------------------
    def declared_type(self, spec: Node | None) -> Type | None:
        """The type a type node of this file names, as the compiler's index builds it (None: unknown)."""
        if spec is None or spec.type not in ("identifier", "elementary_type", "array_type", "string_type"):
            return None  # an inline enum or struct would register its members again
        t = self.index.declared_type(spec, self.ps)
        return None if t.kind == UNKNOWN else t

    def named_type(self, name: str) -> Type | None:
        """A declared data type or function block type by name (None: none)."""
        try:
            t = self.index.resolve_named(name)
        except (KeyError, CompileError):
            return None
        return None if t.kind == UNKNOWN else t

    # ---- reporting -----------------------------------------------------------------------------
    def report(self, node: Node, message: str) -> None:
        self.diagnostics.append(self.ps.diag(node, message))

    def report_end(self, node: Node, message: str) -> None:
        row, col = node.end_point
        self.diagnostics.append(Diagnostic(self.ps.filename, row + 1, col + 1, message))

    def report_offset(self, offset: int, message: str) -> None:
        text = self.lexical.text
        line = text.count("\n", 0, offset) + 1
        col = len(text[text.rfind("\n", 0, offset) + 1 : offset].encode("utf-8")) + 1  # bytes, as tree-sitter
        self.diagnostics.append(Diagnostic(self.ps.filename, line, col, message))
