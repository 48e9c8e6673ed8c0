"""Expressions: variables, operators, member and array access (IEC type + C class + code)."""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.literals import fold, literal, negate
from plc.st.model import NULL_REF, Ex, Var, c_of, type_label
from plc.st.typerules import arith_type, bit_type, common_c, compare_types, literal_c, to_c
from plc.st.types import BOOL, TIME, Type

CMP_OPS = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
ARITH_OPS = {"+", "-", "*", "/", "MOD"}
BIT_OPS = {"AND": "&", "&": "&", "OR": "|", "XOR": "^"}


class ExprGen(Generator):
    def expr(self, node: Node, expected: Type | None = None) -> Ex:
        src = self.ctx.src
        k = node.type
        if k == "parenthesized_expression":
            inner = self.expr(node.named_children[0], expected)
            return Ex(f"({inner.code})", inner.t, inner.c, inner.const)
        if k == "identifier":
            return self.identifier(node, expected)
        lit = literal(self.ctx, node)
        if lit is not None:
            return lit
        if k == "unary_expression":
            return self.unary(node)
        if k == "binary_expression":
            return self.binary(node)
        if k == "call_expression":
            return self.calls.call(node, expected)
        if k == "dereference_expression":
            r = self.expr(node.named_children[0])
            if r.t.kind != "ref" or r.t.elem is None:
                raise self.ctx.err(src, node, f"'^' applied to a value of type {r.t.name}")
            return Ex(f"deref({r.code})", r.t.elem, c_of(r.t.elem))
        if k == "member_access_expression":
            return self.member(node)
        if k == "index_expression":
            return self.index_expr(node)
        raise self.ctx.err(src, node, f"unsupported expression '{src.node_text(node)[:40]}' ({k})")

    def identifier(self, node: Node, expected: Type | None) -> Ex:
        src = self.ctx.src
        if node.start_byte in src.enum_literals:
            tname, member = src.enum_literals[node.start_byte]
            try:
                et = self.index.resolve_named(tname)
            except KeyError:
                raise self.ctx.err(src, node, f"unknown enumerated type '{tname}'") from None
            if et.kind != "enum" or member.upper() not in et.members:
                raise self.ctx.err(src, node, f"'{member}' is not a value of '{tname}'")
            idx = et.members.index(member.upper())
            return Ex(repr(idx), et, "enum", idx)
        name = src.node_text(node).lower()
        pou = self.ctx.pou
        if pou is not None and name in pou.vars:
            code, v = self.ref_var(name, node)
            return Ex(code, v.type, c_of(v.type))
        if pou is not None and pou.kind == "function" and name.upper() == pou.name:
            return Ex("v__ret", pou.ret, c_of(pou.ret))
        if name == "null":
            return Ex("None", NULL_REF, "ref")
        cands = self.index.enum_members.get(name.upper())
        if cands:
            et = cands[0]
            if len(cands) > 1 and expected is not None and expected in cands:
                et = expected
            idx = et.members.index(name.upper())
            return Ex(repr(idx), et, "enum", idx)
        if self.ctx.mode == "config" and name in self.index.globals:
            v = self.index.globals[name]
            return Ex(f"G.v_{name}", v.type, c_of(v.type))
        raise self.ctx.err(src, node, f"variable '{src.node_text(node)}' is not declared in this scope")

    def ref_var(self, name: str, node: Node) -> tuple[str, Var]:
        pou = self.ctx.pou
        v = pou.vars.get(name) if pou else None
        if v is not None:
            if v.section == "ext":
                g = self.index.globals.get(name)
                if g is None:
                    raise self.ctx.err(
                        self.ctx.src, node, f"VAR_EXTERNAL '{name}' has no VAR_GLOBAL in the configuration"
                    )
                return f"G.v_{name}", v
            if self.ctx.mode == "function":
                return f"v_{name}", v
            return f"s.v_{name}", v
        if self.ctx.mode == "config" and name in self.index.globals:
            return f"G.v_{name}", self.index.globals[name]
        raise self.ctx.err(self.ctx.src, node, f"variable '{name}' is not declared in this scope")

    def binary(self, node: Node) -> Ex:
        src = self.ctx.src
        left, opn, right = node.children[0], node.children[1], node.children[2]
        op = src.node_text(opn).upper()
        a = self.expr(left)
        b = self.expr(right, expected=a.t if a.t.kind == "enum" else None)
        if b.t.kind == "enum" and a.t.kind == "enum" and a.t is not b.t and left.type == "identifier":
            a = self.expr(left, expected=b.t)
        if op in ("AND", "&", "OR", "XOR"):
            if a.t.kind == "bool" and b.t.kind == "bool":
                if op == "XOR":
                    return Ex(f"({a.code} != {b.code})", BOOL, "bool")
                pyop = "and" if op in ("AND", "&") else "or"
                return Ex(f"({a.code} {pyop} {b.code})", BOOL, "bool")
            t = bit_type(self.ctx, a, b, op, node)
            a, b = literal_c(a, b), literal_c(b, a)
            c = common_c(a.c, b.c)
            return Ex(f"({to_c(a, c)} {BIT_OPS[op]} {to_c(b, c)})", t, c)
        if op in CMP_OPS:
            if a.t.kind == "ref" or b.t.kind == "ref":
                if op not in ("=", "<>") or a.t.kind != b.t.kind:
                    raise self.ctx.err(
                        src, node, f"'{op}' is not defined for {type_label(a.t)} and {type_label(b.t)}"
                    )
                return Ex(f"({a.code} {'is' if op == '=' else 'is not'} {b.code})", BOOL, "bool")
            compare_types(self.ctx, a, b, op, node)
            a, b = literal_c(a, b), literal_c(b, a)
            if a.c in ("time", "str", "enum", "bool") or b.c in ("time", "str", "enum", "bool"):
                return Ex(f"({a.code} {CMP_OPS[op]} {b.code})", BOOL, "bool")
            c = common_c(a.c, b.c)
            return Ex(f"({to_c(a, c)} {CMP_OPS[op]} {to_c(b, c)})", BOOL, "bool")
        if op in ARITH_OPS:
            t = arith_type(self.ctx, a, b, op, node)
            if t.kind == "time":
                return self.time_arith(a, b, op)
            a, b = literal_c(a, b), literal_c(b, a)
            c = common_c(a.c, b.c)
            if a.const is not None and b.const is not None and t.kind in ("anyint", "anyreal"):
                return fold(self.ctx, a, b, op, t, node)
            x, y = to_c(a, c), to_c(b, c)
            if c in ("f", "d"):
                if op == "MOD":
                    raise self.ctx.err(src, node, "MOD needs integer operands")
                core = f"fdiv({x}, {y})" if op == "/" else f"({x} {op} {y})"
                return Ex(f"f32({core})" if c == "f" else core, t, c)
            if op == "/":
                core = f"idiv({x}, {y})"
            elif op == "MOD":
                core = f"imod({x}, {y})"
            else:
                core = f"({x} {op} {y})"
            wrap = {"i32": "ws32", "u32": "wu32", "i64": "ws64", "u64": "wu64"}[c]
            return Ex(f"{wrap}{core}" if core.startswith("(") else f"{wrap}({core})", t, c)
        raise self.ctx.err(src, node, f"unsupported operator '{op}'")

    def time_arith(self, a: Ex, b: Ex, op: str) -> Ex:
        if op == "+":
            return Ex(f"({a.code} + {b.code})", TIME, "time")
        if op == "-":
            return Ex(f"({a.code} - {b.code})", TIME, "time")
        fn = "time_mul" if op == "*" else "time_div"
        return Ex(f"{fn}({a.code}, {b.code})", TIME, "time")

    def unary(self, node: Node) -> Ex:
        op = self.ctx.src.node_text(node.children[0]).upper()
        a = self.expr(node.named_children[-1])
        if op == "NOT":
            if a.t.kind == "bool":
                return Ex(f"(not {a.code})", BOOL, "bool")
            if a.t.kind in ("int", "anyint"):
                c = a.c
                core = f"(~{a.code})"
                if c in ("u32", "u64"):
                    core = f"w{c}{core}"
                return Ex(core, a.t, c)
            raise self.ctx.err(self.ctx.src, node, f"NOT is not defined for {a.t.name}")
        if op == "-":
            if a.const is not None and a.t.kind in ("anyint", "anyreal"):
                return negate(a)
            if a.c in ("f", "d"):
                return Ex(f"(-{a.code})", a.t, a.c)
            if a.t.kind == "time":
                return Ex(f"(-{a.code})", TIME, "time")
            if a.t.kind in ("int", "anyint"):
                wrap = {"i32": "ws32", "u32": "wu32", "i64": "ws64", "u64": "wu64"}.get(a.c, "ws32")
                return Ex(f"{wrap}(-{a.code})", a.t, a.c)
            raise self.ctx.err(self.ctx.src, node, f"unary '-' is not defined for {a.t.name}")
        if op == "+":
            return a
        raise self.ctx.err(self.ctx.src, node, f"unsupported unary operator '{op}'")

    def member(self, node: Node) -> Ex:
        base = self.expr(node.named_children[0])
        fname = self.ctx.src.node_text(node.named_children[-1]).lower()
        t = base.t
        if t.kind == "struct":
            if fname not in t.fields:
                raise self.ctx.err(self.ctx.src, node, f"'{t.name}' has no field '{fname}'")
            ft = t.fields[fname]
            return Ex(f"{base.code}.v_{fname}", ft, c_of(ft))
        if t.kind == "fb":
            members = self.index.fb_members(t)
            if fname not in members:
                raise self.ctx.err(self.ctx.src, node, f"function block '{t.name}' has no variable '{fname}'")
            ft, section = members[fname]
            if section not in ("in", "out", "inout"):
                raise self.ctx.err(
                    self.ctx.src,
                    node,
                    f"'{fname}' is internal to '{t.name}' (only inputs and outputs are accessible)",
                )
            return Ex(f"{base.code}.v_{fname}", ft, c_of(ft))
        raise self.ctx.err(self.ctx.src, node, f"'.{fname}' applied to a value of type {t.name}")

    def index_expr(self, node: Node) -> Ex:
        base = self.expr(node.named_children[0])
        t = base.t
        if t.kind != "array":
            raise self.ctx.err(self.ctx.src, node, f"indexing a value of type {t.name}")
        idx_nodes = node.named_children[1:]
        if len(idx_nodes) != len(t.dims):
            raise self.ctx.err(
                self.ctx.src, node, f"array has {len(t.dims)} dimension(s), {len(idx_nodes)} index(es) given"
            )
        parts = []
        stride = 1
        strides = []
        for lo, hi in reversed(t.dims):
            strides.append(stride)
            stride *= hi - lo + 1
        strides.reverse()
        for inode, (lo, hi), st in zip(idx_nodes, t.dims, strides, strict=True):
            ie = self.expr(inode)
            if ie.t.kind not in ("int", "anyint", "enum"):
                raise self.ctx.err(self.ctx.src, inode, f"array index must be an integer, not {ie.t.name}")
            n = hi - lo + 1
            if ie.const is not None:
                if not lo <= ie.const <= hi:
                    raise self.ctx.err(
                        self.ctx.src, inode, f"array index {ie.const} out of range [{lo}..{hi}]"
                    )
                k = (ie.const - lo) * st
                parts.append(repr(k))
            else:
                k = f"ix({ie.code}, {lo}, {n})"
                parts.append(k if st == 1 else f"{k} * {st}")
        flat = " + ".join(parts) if parts else "0"
        return Ex(f"{base.code}[{flat}]", t.elem, c_of(t.elem))

    def lvalue(self, node: Node) -> Ex:
        if node.type not in ("identifier", "member_access_expression", "index_expression"):
            raise self.ctx.err(self.ctx.src, node, "a variable is required here")
        e = self.expr(node)
        if e.const is not None:
            raise self.ctx.err(self.ctx.src, node, "cannot assign to a constant")
        return e
