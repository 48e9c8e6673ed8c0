"""State shared by the generators while one POU (or the configuration) is generated.

`GenContext` holds the output lines, the current source, POU and scope mode ("method" in a
FUNCTION_BLOCK / PROGRAM, "function", "config" for initial values of globals), the statements
that must run before the current one (`pre`: function calls with outputs), indentation,
temporaries and loop depth. `Generator` is the base of the per-concern generators; `wire`
lets each one reach the index, the context and its siblings.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from tree_sitter import Node

from plc.st.diagnostics import Diagnostic
from plc.st.model import CompileError, Pou
from plc.st.parser import ParsedSource

if TYPE_CHECKING:
    from plc.st.codegen.calls import CallGen
    from plc.st.codegen.configuration import ConfigGen
    from plc.st.codegen.expressions import ExprGen
    from plc.st.codegen.initialisers import InitGen
    from plc.st.codegen.invocations import InvocationGen
    from plc.st.codegen.pous import PouGen
    from plc.st.codegen.statements import StmtGen
    from plc.st.index import Index


class GenContext:
    def __init__(self, diags: list[Diagnostic], src: ParsedSource | None):
        self.diags = diags
        self.src = src
        self.pou: Pou | None = None
        self.mode = "config"
        self.pre: list[str] = []
        self.out: list[str] = []
        self.indent = 0
        self.tmp = 0
        self.loop_depth = 0
        self.return_code = "return"

    def err(self, src: ParsedSource, node: Node, msg: str) -> CompileError:
        return CompileError(src.diag(node, msg))

    def emit(self, line: str) -> None:
        self.out.append("    " * self.indent + line)

    def flush_pre(self) -> None:
        for p in self.pre:
            self.emit(p)
        self.pre = []

    def new_tmp(self) -> str:
        self.tmp += 1
        return f"_t{self.tmp}"

    def with_src(self, src: ParsedSource, fn: Callable[[], Any]) -> Any:
        saved = self.src
        self.src = src
        try:
            return fn()
        finally:
            self.src = saved


class Generator:
    """Base of the generators: the index, the shared context and the sibling generators."""

    index: Index
    ctx: GenContext
    exprs: ExprGen
    calls: CallGen
    stmts: StmtGen
    invocations: InvocationGen
    inits: InitGen
    pougen: PouGen
    configgen: ConfigGen

    def wire(self, index: Index, ctx: GenContext, gens: dict[str, Generator]) -> None:
        self.index = index
        self.ctx = ctx
        for name, gen in gens.items():
            setattr(self, name, gen)
