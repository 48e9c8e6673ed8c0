"""The checker's per-file state and how a rule reports a finding."""

from __future__ import annotations

from tree_sitter import Node

from plc.checker.lexical import LexicalScan
from plc.checker.symbols import Symbols
from plc.st.diagnostics import Diagnostic
from plc.st.parser import ParsedSource


class CheckerBase:
    """One file under check: its parse, lexical scan, the declarations of the whole run, the findings."""

    def __init__(self, ps: ParsedSource, lexical: LexicalScan, symbols: Symbols):
        self.ps = ps
        self.lexical = lexical
        self.symbols = symbols
        self.diagnostics: list[Diagnostic] = []

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
