"""Stage 4: Python code from the index, one generator per concern (see docs/architecture.md)."""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.calls import CallGen
from plc.st.codegen.configuration import ConfigGen
from plc.st.codegen.context import GenContext, Generator
from plc.st.codegen.expressions import ExprGen
from plc.st.codegen.initialisers import InitGen
from plc.st.codegen.invocations import InvocationGen
from plc.st.codegen.pous import PouGen
from plc.st.codegen.statements import StmtGen
from plc.st.index import Index
from plc.st.model import CompileError
from plc.st.parser import ParsedSource
from plc.st.typerules import convert_store
from plc.st.types import Type

Instances = list[tuple[str, str, int]]  # (instance, class, interval_ns)


def _generators(index: Index, ctx: GenContext) -> dict[str, Generator]:
    gens: dict[str, Generator] = {
        "exprs": ExprGen(),
        "calls": CallGen(),
        "stmts": StmtGen(),
        "invocations": InvocationGen(),
        "inits": InitGen(),
        "pougen": PouGen(),
        "configgen": ConfigGen(),
    }
    for gen in gens.values():
        gen.wire(index, ctx, gens)
    return gens


def generate(index: Index) -> tuple[str, Instances]:
    """Python source of the indexed program (diagnostics go to index.diags) and its instances."""
    ctx = GenContext(index.diags, index.sources[0] if index.sources else None)
    gens = _generators(index, ctx)
    for pou in index.pous.values():
        if pou.failed:
            continue
        try:
            gens["pougen"].gen_pou(pou)
        except CompileError as e:
            index.diags.append(e.diag)
    instances = gens["configgen"].gen_config()
    structs = gens["inits"].gen_structs()
    return "\n".join(structs + ctx.out) + "\n", instances


def initial_value_fits(index: Index, src: ParsedSource, value: Node, target: Type) -> bool:
    """Whether the typing rules accept `value` as an initial value of a variable of type `target`."""
    ctx = GenContext([], src)
    exprs = _generators(index, ctx)["exprs"]
    try:
        convert_store(ctx, exprs.expr(value, target), target, value, what="initial value")
    except CompileError:
        return False
    return True
