"""Statements: assignment, IF / CASE / FOR / WHILE / REPEAT, EXIT / CONTINUE / RETURN and
function block / function invocations.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.literals import lit_int
from plc.st.model import CompileError
from plc.st.typerules import convert_store


class StmtGen(Generator):
    def body(self, nodes: list[Node]) -> None:
        start = len(self.ctx.out)
        for st in nodes:
            try:
                self.statement(st)
            except CompileError as e:
                self.ctx.diags.append(e.diag)
                self.ctx.pre = []
        if len(self.ctx.out) == start:
            self.ctx.emit("pass")

    def cond(self, node: Node) -> str:
        e = self.exprs.expr(node)
        if e.t.kind != "bool":
            raise self.ctx.err(self.ctx.src, node, f"condition must be BOOL, not {e.t.name}")
        return e.code

    def statement(self, st: Node) -> None:
        k = st.type
        src = self.ctx.src
        if k in ("empty_statement", "comment"):
            return
        if k == "assignment_statement":
            target = st.named_children[0]
            value = st.named_children[-1]
            lv = self.exprs.lvalue(target)
            e = self.exprs.expr(value, lv.t)
            code = convert_store(self.ctx, e, lv.t, st)
            self.ctx.flush_pre()
            self.ctx.emit(f"{lv.code} = {code}")
            return
        if k == "invocation_statement":
            self.invocations.invocation(st.named_children[0])
            return
        if k == "if_statement":
            self.if_statement(st)
            return
        if k == "case_statement":
            self.case_statement(st)
            return
        if k == "for_statement":
            self.for_statement(st)
            return
        if k == "while_statement":
            kids = [c for c in st.named_children if c.type != "comment"]
            self.ctx.emit("while True:")
            self.ctx.indent += 1
            c = self.cond(kids[0])
            self.ctx.flush_pre()
            self.ctx.emit(f"if not {c}:")
            self.ctx.emit("    break")
            self.ctx.loop_depth += 1
            self.body(kids[1:])
            self.ctx.loop_depth -= 1
            self.ctx.indent -= 1
            return
        if k == "repeat_statement":
            kids = [c for c in st.named_children if c.type != "comment"]
            flag = self.ctx.new_tmp()
            cond_node = kids[-1]
            self.ctx.emit(f"{flag} = True")
            c = self.cond(cond_node)
            if self.ctx.pre:
                raise self.ctx.err(src, cond_node, "UNTIL condition with function outputs is not supported")
            self.ctx.emit(f"while {flag} or not {c}:")
            self.ctx.indent += 1
            self.ctx.emit(f"{flag} = False")
            self.ctx.loop_depth += 1
            self.body(kids[:-1])
            self.ctx.loop_depth -= 1
            self.ctx.indent -= 1
            return
        if k == "exit_statement":
            if not self.ctx.loop_depth:
                raise self.ctx.err(src, st, "EXIT outside a loop")
            self.ctx.emit("break")
            return
        if k == "continue_statement":
            if not self.ctx.loop_depth:
                raise self.ctx.err(src, st, "CONTINUE outside a loop")
            self.ctx.emit("continue")
            return
        if k == "return_statement":
            self.ctx.emit(self.ctx.return_code)
            return
        raise self.ctx.err(src, st, f"unsupported statement '{src.node_text(st)[:40]}' ({k})")

    def if_statement(self, st: Node) -> None:
        kids = [c for c in st.children if c.type != "comment"]
        # IF c THEN stmts {ELSIF c THEN stmts} [ELSE stmts] END_IF
        i = 0
        depth = 0
        first = True
        while i < len(kids):
            c = kids[i]
            if c.type in ("IF", "ELSIF") or (c.type == "elsif_clause"):
                if c.type == "elsif_clause":
                    sub = [x for x in c.children if x.type != "comment"]
                    cond_node = sub[1]
                    stmts = [x for x in sub[3:] if x.is_named]
                    i += 1
                else:
                    cond_node = kids[i + 1]
                    j = i + 3
                    stmts = []
                    while j < len(kids) and kids[j].type not in (
                        "ELSIF",
                        "ELSE",
                        "END_IF",
                        "elsif_clause",
                        "else_clause",
                    ):
                        if kids[j].is_named:
                            stmts.append(kids[j])
                        j += 1
                    i = j
                c_code = self.cond(cond_node)
                if first:
                    self.ctx.flush_pre()
                    self.ctx.emit(f"if {c_code}:")
                elif self.ctx.pre:
                    self.ctx.emit("else:")
                    self.ctx.indent += 1
                    depth += 1
                    self.ctx.flush_pre()
                    self.ctx.emit(f"if {c_code}:")
                else:
                    self.ctx.emit(f"elif {c_code}:")
                first = False
                self.ctx.indent += 1
                self.body(stmts)
                self.ctx.indent -= 1
            elif c.type in ("else_clause", "ELSE"):
                if c.type == "else_clause":
                    stmts = [x for x in c.named_children if x.type != "comment"]
                    i += 1
                else:
                    j = i + 1
                    stmts = []
                    while j < len(kids) and kids[j].type != "END_IF":
                        if kids[j].is_named:
                            stmts.append(kids[j])
                        j += 1
                    i = j
                self.ctx.emit("else:")
                self.ctx.indent += 1
                self.body(stmts)
                self.ctx.indent -= 1
            else:
                i += 1
        self.ctx.indent -= depth

    def case_statement(self, st: Node) -> None:
        kids = [c for c in st.named_children if c.type != "comment"]
        sel = self.exprs.expr(kids[0])
        tmp = self.ctx.new_tmp()
        if sel.t.kind == "int":
            code = f"w{'s' if sel.t.signed else 'u'}{sel.t.bits}({sel.code})"
        else:
            code = sel.code
        self.ctx.flush_pre()
        self.ctx.emit(f"{tmp} = {code}")
        first = True
        for clause in kids[1:]:
            if clause.type == "case_clause":
                conds = []
                stmts = []
                for c in clause.named_children:
                    if c.type == "case_value":
                        v = c.named_children[0]
                        if v.type == "subrange":
                            lo, hi = (self.exprs.expr(x, sel.t) for x in v.named_children)
                            conds.append(f"{lo.code} <= {tmp} <= {hi.code}")
                        else:
                            e = self.exprs.expr(v, sel.t if sel.t.kind == "enum" else None)
                            if sel.t.kind == "enum" and e.t is not sel.t and v.type == "identifier":
                                raise self.ctx.err(
                                    self.ctx.src,
                                    v,
                                    f"'{self.ctx.src.node_text(v)}' is not a value of {sel.t.name}",
                                )
                            conds.append(f"{tmp} == {e.code}")
                    elif c.type != "comment":
                        stmts.append(c)
                self.ctx.emit(f"{'if' if first else 'elif'} {' or '.join(conds) or 'False'}:")
                first = False
                self.ctx.indent += 1
                self.body(stmts)
                self.ctx.indent -= 1
            elif clause.type == "else_clause":
                stmts = [x for x in clause.named_children if x.type != "comment"]
                if first:
                    self.ctx.emit("if True:")
                else:
                    self.ctx.emit("else:")
                first = False
                self.ctx.indent += 1
                self.body(stmts)
                self.ctx.indent -= 1

    def for_statement(self, st: Node) -> None:
        kids = st.children
        var_node = kids[1]
        # children: FOR id := start TO end [BY step] DO stmts END_FOR
        to_i = next(i for i, c in enumerate(kids) if c.type == "TO")
        do_i = next(i for i, c in enumerate(kids) if c.type == "DO")
        by_i = next((i for i, c in enumerate(kids) if c.type == "BY"), None)
        start_node = kids[to_i - 1]
        end_node = kids[to_i + 1]
        step_node = kids[by_i + 1] if by_i is not None else None
        stmts = [c for c in kids[do_i + 1 :] if c.is_named and c.type != "comment"]
        lv = self.exprs.lvalue(var_node)
        if lv.t.kind != "int":
            raise self.ctx.err(self.ctx.src, var_node, "FOR variable must be an integer variable")
        start = convert_store(self.ctx, self.exprs.expr(start_node), lv.t, start_node)
        end = self.exprs.expr(end_node)
        convert_store(self.ctx, end, lv.t, end_node)
        step = self.exprs.expr(step_node) if step_node is not None else lit_int(1)
        convert_store(self.ctx, step, lv.t, step_node or st)
        wrap = f"w{'s' if lv.t.signed else 'u'}{lv.t.bits}"
        flag = self.ctx.new_tmp()
        self.ctx.flush_pre()
        self.ctx.emit(f"{lv.code} = {start}")
        self.ctx.emit(f"{flag} = True")
        self.ctx.emit("while True:")
        self.ctx.indent += 1
        self.ctx.emit(f"if not {flag}:")
        self.ctx.emit(f"    {lv.code} = {wrap}({lv.code} + {step.code})")
        self.ctx.emit(f"{flag} = False")
        if step.const is not None:
            cmp = "<=" if step.const > 0 else ">="
            self.ctx.emit(f"if not ({lv.code} {cmp} {end.code}):")
        else:
            self.ctx.emit(
                f"if not (({lv.code} <= {end.code}) if {step.code} > 0 else ({lv.code} >= {end.code})):"
            )
        self.ctx.emit("    break")
        self.ctx.loop_depth += 1
        self.body(stmts)
        self.ctx.loop_depth -= 1
        self.ctx.indent -= 1
