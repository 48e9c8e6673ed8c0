"""Calls in expressions: user FUNCTIONs (outputs through a temporary), standard functions,
`X_TO_Y` conversions and REF().
"""

from __future__ import annotations

import re

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.model import Ex, Pou, Var, c_of
from plc.st.typerules import as_type, common_arg_type, convert_store, same_array
from plc.st.types import ANY_INT, BOOL, ELEMENTARY, REAL, STRING, TIME, Type

MATH_FUNCS = {
    "SQRT": "sqrt",
    "EXP": "exp",
    "LN": "ln",
    "LOG": "log10",
    "SIN": "sin",
    "COS": "cos",
    "TAN": "tan",
    "ASIN": "asin",
    "ACOS": "acos",
    "ATAN": "atan",
}
CONV_RE = re.compile(r"^([A-Z_]+?)_TO_([A-Z_]+)$")


class CallGen(Generator):
    def call_args(self, node: Node) -> tuple[list[Node], dict[str, tuple[Node, str]]]:
        arglist = node.named_children[-1]
        positional: list[Node] = []
        named: dict[str, tuple[Node, str]] = {}
        for a in arglist.named_children:
            if a.type == "named_argument":
                kids = a.children
                pname = self.ctx.src.node_text(kids[0]).lower()
                arrow = self.ctx.src.node_text(kids[1])
                value = kids[2] if len(kids) > 2 else None
                negated = False
                if kids[0].type == "NOT":
                    negated = True
                named[pname] = (value, "=>" if arrow == "=>" else ":=") if not negated else (value, "=>!")
            elif a.type != "comment":
                positional.append(a)
        return positional, named

    def call(self, node: Node, expected: Type | None = None) -> Ex:
        fname_node = node.named_children[0]
        if fname_node.type != "identifier":
            raise self.ctx.err(self.ctx.src, node, "only named functions can be called in an expression")
        name = self.ctx.src.node_text(fname_node).upper()
        positional, named = self.call_args(node)
        if name in self.index.pous and self.index.pous[name].kind == "function":
            return self.user_call(self.index.pous[name], positional, named, node)
        if self.ctx.pou is not None and name.lower() in self.ctx.pou.vars:
            raise self.ctx.err(
                self.ctx.src, node, "function block instances are called as statements, not in expressions"
            )
        if named and name not in self.index.pous:
            # standard functions called with formal names (IN1 := ...) map to their positions
            order = sorted(named)
            positional = positional + [named[k][0] for k in order]
        args = [self.exprs.expr(a) for a in positional]
        if name == "REF":
            if len(positional) != 1:
                raise self.ctx.err(self.ctx.src, node, "REF takes one variable")
            target = self.exprs.lvalue(positional[0])
            return Ex(
                f"Ref(lambda: {target.code})", Type(f"REF_TO {target.t.name}", "ref", elem=target.t), "ref"
            )
        m = CONV_RE.match(name)
        if m and len(args) == 1:
            return self.conversion(m.group(1), m.group(2), args[0], node)
        return self.std_call(name, args, node)

    def conversion(self, frm: str, to: str, a: Ex, node: Node) -> Ex:
        src_t = ELEMENTARY.get(frm)
        dst = ELEMENTARY.get(to)
        if src_t is None or dst is None:
            raise self.ctx.err(self.ctx.src, node, f"unknown conversion function {frm}_TO_{to}")
        x = convert_store(self.ctx, a, src_t, node, what=f"{frm}_TO_{to} argument")
        if dst.kind == "int":
            wrap = f"w{'s' if dst.signed else 'u'}{dst.bits}"
            if src_t.kind in ("int", "bool"):
                return Ex(f"{wrap}(int({x}))" if src_t.kind == "bool" else f"{wrap}({x})", dst, c_of(dst))
            if src_t.kind == "real":
                fn = "real_to_sint" if dst.signed else "real_to_uint"
                return Ex(f"{wrap}({fn}({x}))", dst, c_of(dst))
            if src_t.kind == "time":
                return Ex(f"{wrap}(time_to_int({x}))", dst, c_of(dst))
        if dst.kind == "real":
            if src_t.kind in ("int", "bool"):
                core = f"float({x})"
            elif src_t.kind == "real":
                core = x
            elif src_t.kind == "time":
                core = f"time_to_lreal({x})"
            else:
                core = None
            if core is not None:
                return Ex(f"f32({core})" if dst is REAL else core, dst, c_of(dst))
        if dst.kind == "bool":
            if src_t.kind in ("int", "real"):
                return Ex(f"({x} != 0)", BOOL, "bool")
        if dst.kind == "time":
            if src_t.kind == "int":
                return Ex(f"int_to_time({x})", TIME, "time")
            if src_t.kind == "real":
                return Ex(f"real_to_time({x})", TIME, "time")
            if src_t.kind == "time":
                return Ex(x, TIME, "time")
        raise self.ctx.err(self.ctx.src, node, f"conversion {frm}_TO_{to} is not supported")

    def std_call(self, name: str, args: list[Ex], node: Node) -> Ex:
        n = len(args)

        def need(k: int) -> None:
            if n != k:
                raise self.ctx.err(self.ctx.src, node, f"{name} takes {k} argument(s), {n} given")

        if name in MATH_FUNCS or name == "ABS":
            need(1)
            a = args[0]
            if name == "ABS":
                if a.t.kind == "int":
                    return Ex(f"w{'s' if a.t.signed else 'u'}{a.t.bits}(abs_int({a.code}))", a.t, a.c)
                if a.t.kind == "anyint":
                    return Ex(f"abs_int({a.code})", a.t, a.c)
                if a.t.kind in ("real", "anyreal"):
                    return Ex(f"abs_float({a.code})", a.t, a.c)
                raise self.ctx.err(self.ctx.src, node, f"ABS is not defined for {a.t.name}")
            if a.t.kind not in ("real", "anyreal"):
                raise self.ctx.err(
                    self.ctx.src, node, f"{name} needs a REAL or LREAL argument, not {a.t.name}"
                )
            core = f"{MATH_FUNCS[name]}({a.code})"
            return Ex(f"f32({core})" if a.t is REAL else core, a.t, "f" if a.t is REAL else "d")
        if name == "EXPT":
            need(2)
            a, b = args
            if a.t.kind not in ("real", "anyreal"):
                raise self.ctx.err(self.ctx.src, node, f"EXPT needs a REAL or LREAL base, not {a.t.name}")
            if not b.t.is_num():
                raise self.ctx.err(self.ctx.src, node, "EXPT exponent must be numeric")
            core = f"expt({a.code}, {b.code})"
            return Ex(f"f32({core})" if a.t is REAL else core, a.t, "f" if a.t is REAL else "d")
        if name in ("MIN", "MAX"):
            if n < 2:
                raise self.ctx.err(self.ctx.src, node, f"{name} needs at least 2 arguments")
            t = common_arg_type(self.ctx, args, node, name)
            codes = [as_type(self.ctx, a, t, node, name) for a in args]
            return Ex(
                f"{name.lower()}({', '.join(codes)})",
                t,
                c_of(t) if t.kind not in ("anyint", "anyreal") else args[0].c,
            )
        if name == "LIMIT":
            need(3)
            t = common_arg_type(self.ctx, args, node, name)
            codes = [as_type(self.ctx, a, t, node, name) for a in args]
            c = c_of(t) if t.kind not in ("anyint", "anyreal") else ("d" if t.kind == "anyreal" else "i32")
            return Ex(f"limit({', '.join(codes)})", t, c)
        if name == "SEL":
            need(3)
            g = args[0]
            if g.t.kind != "bool":
                raise self.ctx.err(self.ctx.src, node, "SEL selector must be BOOL")
            t = common_arg_type(self.ctx, args[1:], node, name)
            a, b = (as_type(self.ctx, x, t, node, name) for x in args[1:])
            c = c_of(t) if t.kind not in ("anyint", "anyreal") else args[1].c
            return Ex(f"({b} if {g.code} else {a})", t, c)
        if name == "MUX":
            if n < 2:
                raise self.ctx.err(self.ctx.src, node, "MUX needs a selector and at least one input")
            k = args[0]
            if k.t.kind not in ("int", "anyint"):
                raise self.ctx.err(self.ctx.src, node, "MUX selector must be an integer")
            t = common_arg_type(self.ctx, args[1:], node, name)
            codes = [as_type(self.ctx, x, t, node, name) for x in args[1:]]
            c = c_of(t) if t.kind not in ("anyint", "anyreal") else args[1].c
            return Ex(f"mux({k.code}, {', '.join(codes)})", t, c)
        if name in ("SHL", "SHR", "ROL", "ROR"):
            need(2)
            a, b = args
            if a.t.kind != "int":
                raise self.ctx.err(
                    self.ctx.src, node, f"{name} needs a typed bit-string/integer first argument"
                )
            return Ex(f"{name.lower()}({a.code}, {b.code}, {a.t.bits})", a.t, c_of(a.t))
        if name == "TRUNC":
            need(1)
            a = args[0]
            if a.t.kind not in ("real", "anyreal"):
                raise self.ctx.err(self.ctx.src, node, "TRUNC needs a REAL or LREAL argument")
            return Ex(f"trunc({a.code})", ANY_INT, "i64")
        if name == "MOVE":
            need(1)
            return args[0]
        if name == "LEN":
            need(1)
            return Ex(f"len({args[0].code})", ELEMENTARY["INT"], "i32")
        if name == "CONCAT":
            return Ex("(" + " + ".join(a.code for a in args) + ")", STRING, "str")
        if name in ("LEFT", "RIGHT"):
            need(2)
            s_, n_ = args
            if name == "LEFT":
                return Ex(f"{s_.code}[:max(0, {n_.code})]", STRING, "str")
            return Ex(f"({s_.code}[-{n_.code}:] if {n_.code} > 0 else '')", STRING, "str")
        if name == "MID":
            need(3)
            s_, n_, p_ = args  # MID(IN, L, P): L characters from position P (1-based)
            return Ex(
                f"{s_.code}[max(0, {p_.code} - 1):max(0, {p_.code} - 1) + max(0, {n_.code})]", STRING, "str"
            )
        if name == "FIND":
            need(2)
            return Ex(f"({args[0].code}.find({args[1].code}) + 1)", ELEMENTARY["INT"], "i32")
        raise self.ctx.err(self.ctx.src, node, f"unknown function '{name}'")

    def user_call(
        self, pou: Pou, positional: list[Node], named: dict, node: Node, statement: bool = False
    ) -> Ex:
        params = pou.params()
        if not params and not statement:
            raise self.ctx.err(
                self.ctx.src,
                node,
                f"no parameter defined in function invocation of '{pou.name}' "
                "(MatIEC needs at least one input)",
            )
        if len(positional) > len(params):
            raise self.ctx.err(self.ctx.src, node, f"too many arguments for '{pou.name}'")
        bound: dict[str, Node] = {}
        for p, a in zip(params, positional, strict=False):
            bound[p.name] = a
        outs: list[tuple[str, Node]] = []
        for pname, (value, kind) in named.items():
            if kind.startswith("=>"):
                if pname not in pou.vars or pou.vars[pname].section != "out":
                    raise self.ctx.err(self.ctx.src, node, f"'{pname}' is not an output of '{pou.name}'")
                outs.append((pname, value))
            else:
                if pname not in pou.vars or pou.vars[pname].section not in ("in", "inout"):
                    raise self.ctx.err(self.ctx.src, node, f"'{pname}' is not an input of '{pou.name}'")
                bound[pname] = value
        codes = []
        writeback: list[tuple[int, Ex, Var]] = []
        for p in params:
            if p.name not in bound:
                if p.section == "inout":
                    raise self.ctx.err(
                        self.ctx.src, node, f"VAR_IN_OUT '{p.name}' of '{pou.name}' must be given"
                    )
                codes.append("None")
                continue
            a = bound[p.name]
            if p.section == "inout":
                lv = self.exprs.lvalue(a)
                if lv.t.name != p.type.name and not (lv.t.kind == "array" and same_array(lv.t, p.type)):
                    raise self.ctx.err(
                        self.ctx.src, a, f"VAR_IN_OUT '{p.name}' needs {p.type.name}, got {lv.t.name}"
                    )
                codes.append(lv.code)
                if p.type.kind not in ("struct", "array", "fb"):
                    writeback.append((0, lv, p))
            else:
                codes.append(
                    convert_store(
                        self.ctx,
                        self.exprs.expr(a, p.type),
                        p.type,
                        a,
                        what=f"parameter '{p.decl_name or p.name}' of {pou.name}",
                    )
                )
        call = f"{pou.pyname}({', '.join(codes)})"
        if not pou.outputs() and not any(
            p.section == "inout" and p.type.kind not in ("struct", "array", "fb") for p in params
        ):
            return Ex(call, pou.ret, c_of(pou.ret))
        tmp = self.ctx.new_tmp()
        self.ctx.pre.append(f"{tmp} = {call}")
        out_index = {v.name: i + 1 for i, v in enumerate(pou.outputs())}
        base = 1 + len(pou.outputs())
        scalar_inouts = [
            p for p in params if p.section == "inout" and p.type.kind not in ("struct", "array", "fb")
        ]
        for pname, target in outs:
            if target is None:
                continue
            lv = self.exprs.lvalue(target)
            ov = pou.vars[pname]
            val = Ex(f"{tmp}[{out_index[pname]}]", ov.type, c_of(ov.type))
            self.ctx.pre.append(f"{lv.code} = {convert_store(self.ctx, val, lv.t, target)}")
        for i, p in enumerate(scalar_inouts):
            lv = next(w[1] for w in writeback if w[2] is p)
            self.ctx.pre.append(f"{lv.code} = {tmp}[{base + i}]")
        return Ex(f"{tmp}[0]", pou.ret, c_of(pou.ret))
