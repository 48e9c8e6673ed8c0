"""POU layout: a FUNCTION becomes a Python function, a FUNCTION_BLOCK / PROGRAM a class with
`__slots__`, `__init__` (initial values), `_copy` and `_run` (the body).
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.model import SECTION_OF, CompileError, Pou


class PouGen(Generator):
    def gen_pou(self, pou: Pou) -> None:
        self.ctx.pou = pou
        self.ctx.src = pou.src
        self.ctx.tmp = 0
        self.ctx.pre = []
        self.ctx.loop_depth = 0
        if pou.kind == "function":
            self.gen_function(pou)
        else:
            self.gen_class(pou)

    def statement_nodes(self, pou: Pou) -> list[Node]:
        out = []
        for c in pou.node.named_children:
            if c.type in SECTION_OF or c.type == "comment":
                continue
            if c.type.endswith("_statement") or c.type in ("empty_statement",):
                out.append(c)
        return out

    def gen_class(self, pou: Pou) -> None:
        self.ctx.mode = "method"
        names = [n for n in pou.order if pou.vars[n].section != "ext"]
        slots = ", ".join(repr(f"v_{n}") for n in names)
        self.ctx.indent = 0
        self.ctx.emit(f"class {pou.pyname}:")
        self.ctx.indent = 1
        self.ctx.emit(f"__slots__ = ({slots}{',' if len(names) == 1 else ''})")
        self.ctx.emit("def __init__(self):")
        self.ctx.indent = 2
        self.ctx.emit("s = self")
        for n in names:
            v = pou.vars[n]
            try:
                self.ctx.emit(f"s.v_{n} = {self.inits.init_code(v.type, v.init)}")
            except CompileError as e:
                self.ctx.diags.append(e.diag)
        self.ctx.emit("pass")
        self.ctx.indent = 1
        self.ctx.emit("def _copy(self):")
        self.ctx.emit(f"    n = {pou.pyname}.__new__({pou.pyname})")
        for n in names:
            self.ctx.emit(f"    n.v_{n} = {self.inits.copy_code(pou.vars[n].type, f'self.v_{n}')}")
        self.ctx.emit("    return n")
        self.ctx.emit("def _run(self):")
        self.ctx.indent = 2
        self.ctx.emit("s = self")
        for n in names:
            v = pou.vars[n]
            if v.section == "temp":
                self.ctx.emit(f"s.v_{n} = {self.inits.init_code(v.type, v.init)}")
        self.ctx.return_code = "return"
        self.stmts.body(self.statement_nodes(pou))
        self.ctx.indent = 0
        self.ctx.emit("")

    def gen_function(self, pou: Pou) -> None:
        self.ctx.mode = "function"
        params = pou.params()
        outputs = pou.outputs()
        scalar_inouts = [
            p for p in params if p.section == "inout" and p.type.kind not in ("struct", "array", "fb")
        ]
        self.ctx.indent = 0
        self.ctx.emit(f"def {pou.pyname}({', '.join('v_' + p.name for p in params)}):")
        self.ctx.indent = 1
        for p in params:
            if p.section == "in":
                self.ctx.emit(f"if v_{p.name} is None:")
                self.ctx.emit(f"    v_{p.name} = {self.inits.init_code(p.type, p.init)}")
        self.ctx.emit(f"v__ret = {self.inits.default_code(pou.ret)}")
        for n in pou.order:
            v = pou.vars[n]
            if v.section in ("var", "temp", "out"):
                if v.type.kind == "fb":
                    self.ctx.diags.append(
                        v.src.diag(
                            pou.node,
                            f"function block instance '{n}' declared inside "
                            f"FUNCTION '{pou.name}' (MatIEC rejects it)",
                        )
                    )
                    continue
                try:
                    self.ctx.emit(f"v_{n} = {self.inits.init_code(v.type, v.init)}")
                except CompileError as e:
                    self.ctx.diags.append(e.diag)
        if outputs or scalar_inouts:
            ret = "return (v__ret, " + "".join(f"v_{v.name}, " for v in outputs + scalar_inouts) + ")"
        else:
            ret = "return v__ret"
        self.ctx.return_code = ret
        self.stmts.body(self.statement_nodes(pou))
        self.ctx.emit(ret)
        self.ctx.indent = 0
        self.ctx.emit("")
