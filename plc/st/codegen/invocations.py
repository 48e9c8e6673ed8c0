"""Invocation statements: a function block instance called with inputs (`:=`), outputs (`=>`) and
VAR_IN_OUTs, or a FUNCTION called as a statement.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.model import Ex, c_of
from plc.st.typerules import convert_store
from plc.st.types import Type


class InvocationGen(Generator):
    def invocation(self, call: Node) -> None:
        target = call.named_children[0]
        positional, named = self.calls.call_args(call)
        if target.type == "identifier":
            name = self.ctx.src.node_text(target).upper()
            if (
                name in self.index.pous
                and self.index.pous[name].kind == "function"
                and (self.ctx.pou is None or name.lower() not in self.ctx.pou.vars)
            ):
                e = self.calls.user_call(self.index.pous[name], positional, named, call, statement=True)
                self.ctx.flush_pre()
                if not e.code.startswith("_t"):
                    self.ctx.emit(e.code)
                return
        fb = self.exprs.expr(target)
        if fb.t.kind != "fb":
            raise self.ctx.err(
                self.ctx.src, call, f"'{self.ctx.src.node_text(target)}' is not a function block instance"
            )
        members = self.index.fb_members(fb.t)
        inputs = [n for n, (_, sec) in members.items() if sec in ("in", "inout")]
        if len(positional) > len(inputs):
            raise self.ctx.err(self.ctx.src, call, "too many positional arguments in function block call")
        assigns = list(zip(inputs, positional, strict=False))
        outs = []
        for pname, (value, kind) in named.items():
            if pname not in members:
                raise self.ctx.err(
                    self.ctx.src, call, f"function block '{fb.t.name}' has no variable '{pname}'"
                )
            if kind.startswith("=>"):
                outs.append((pname, value))
            else:
                assigns.append((pname, value))
        # the instance is looked up once per call: later lines use a local bound to it
        inst = self.ctx.new_tmp()
        target_code, fb = fb.code, Ex(inst, fb.t, fb.c)
        lines = []
        inouts_back = []
        for pname, value in assigns:
            mt, sec = members[pname]
            if sec not in ("in", "inout"):
                raise self.ctx.err(self.ctx.src, call, f"'{pname}' is not an input of '{fb.t.name}'")
            if sec == "inout":
                lv = self.exprs.lvalue(value)
                lines.append(f"{fb.code}.v_{pname} = {lv.code}")
                if mt.kind not in ("struct", "array", "fb"):
                    inouts_back.append(f"{lv.code} = {fb.code}.v_{pname}")
            else:
                e = self.exprs.expr(value, mt)
                what = f"parameter '{self.declared_name(fb.t, pname)}' of {fb.t.name}"
                lines.append(f"{fb.code}.v_{pname} = {convert_store(self.ctx, e, mt, value, what=what)}")
        self.ctx.flush_pre()
        self.ctx.emit(f"{inst} = {target_code}")
        for ln in lines:
            self.ctx.emit(ln)
        self.ctx.emit(f"{fb.code}._run()")
        for ln in inouts_back:
            self.ctx.emit(ln)
        for pname, target_node in outs:
            mt, sec = members[pname]
            lv = self.exprs.lvalue(target_node)
            val = Ex(f"{fb.code}.v_{pname}", mt, c_of(mt))
            self.ctx.emit(f"{lv.code} = {convert_store(self.ctx, val, lv.t, target_node)}")

    @staticmethod
    def declared_name(fb_type: Type, member: str) -> str:
        """A member's name as its declaration writes it (standard blocks: upper case)."""
        pou = fb_type.pou
        if isinstance(pou, str) or pou is None:
            return member.upper()
        var = pou.vars.get(member)
        return var.decl_name if var is not None and var.decl_name else member
