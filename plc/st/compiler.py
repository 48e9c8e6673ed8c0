"""Compile IEC 61131-3 ST (MatIEC dialect and semantics) to Python source, once.

The generated module has one class per STRUCT / FUNCTION_BLOCK / PROGRAM and one Python
function per FUNCTION; a scan calls the program instances' `_run()` methods. Every
expression is typed twice: its IEC type (for MatIEC's type rules and diagnostics) and
the C type MatIEC's generated code gives it (for float/double and integer promotion).
"""

from __future__ import annotations

import calendar
import math
import re
from dataclasses import dataclass, field

from tree_sitter import Node

from plc.st import rt, stdfbs
from plc.st.app import Application, LocatedVar
from plc.st.diagnostics import Diagnostic, StError
from plc.st.parser import ParsedSource, parse_source
from plc.st.types import ANY_INT, ANY_REAL, BOOL, ELEMENTARY, REAL, STRING, TIME, Type

SECTION_OF = {
    "var_input": "in",
    "var_output": "out",
    "var_in_out": "inout",
    "var_block": "var",
    "var_temp": "temp",
    "var_external": "ext",
    "var_global": "global",
}
CMP_OPS = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
ARITH_OPS = {"+", "-", "*", "/", "MOD"}
BIT_OPS = {"AND": "&", "&": "&", "OR": "|", "XOR": "^"}
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
PY_PREFIX = {"function": "FN", "function_block": "FB", "program": "PR"}
CONV_RE = re.compile(r"^([A-Z_]+?)_TO_([A-Z_]+)$")


class _Err(Exception):
    def __init__(self, diag: Diagnostic):
        self.diag = diag


@dataclass
class Var:
    name: str  # lower-case
    type: Type
    section: str
    init: Node | None = None
    location: str | None = None
    constant: bool = False
    src: ParsedSource | None = None
    decl_name: str = ""  # as written in the source (the register map keeps the user's spelling)


@dataclass
class Pou:
    kind: str  # function function_block program
    name: str  # upper-case
    node: Node
    src: ParsedSource
    ret: Type | None = None
    vars: dict[str, Var] = field(default_factory=dict)
    order: list[str] = field(default_factory=list)
    pyname: str = ""
    failed: bool = False

    def params(self) -> list[Var]:
        return [self.vars[n] for n in self.order if self.vars[n].section in ("in", "inout")]

    def outputs(self) -> list[Var]:
        return [self.vars[n] for n in self.order if self.vars[n].section == "out"]


@dataclass
class Ex:
    code: str
    t: Type  # IEC type (ANY_INT / ANY_REAL for untyped literals and their combinations)
    c: str  # C class: i32 u32 i64 u64 f d bool time str enum struct array fb
    const: object = None  # compile-time value for literals


NULL_REF = Type("NULL", "ref")


def _c_of(t: Type) -> str:
    if t.kind in ("struct", "array", "fb", "string", "time", "ref"):
        return t.kind
    if t.kind == "bool":
        return "bool"
    return t.ctype


def _tn(t: Type) -> str:
    """Type name for messages (untyped literals read as such)."""
    return {"anyint": "integer literal", "anyreal": "real literal"}.get(t.kind, t.name)


def _int_range(t: Type) -> tuple[int, int]:
    if t.signed:
        return -(1 << (t.bits - 1)), (1 << (t.bits - 1)) - 1
    return 0, (1 << t.bits) - 1


def _py_float(x: float) -> str:
    if x != x:
        return "NAN"
    if math.isinf(x):
        return "INF" if x > 0 else "(-INF)"
    return repr(float(x))


class Compiler:
    def __init__(self, sources: list[ParsedSource]):
        self.sources = sources
        self.diags: list[Diagnostic] = []
        self.types: dict[str, Type] = {}
        self.type_nodes: dict[str, tuple[Node, ParsedSource]] = {}
        self.enum_members: dict[str, list[Type]] = {}
        self.pous: dict[str, Pou] = {}
        self.config: tuple[Node, ParsedSource] | None = None
        self.globals: dict[str, Var] = {}
        self.out: list[str] = []
        self.tmp = 0

    # ------------------------------------------------------------------ errors
    def err(self, src: ParsedSource, node: Node, msg: str) -> _Err:
        return _Err(src.diag(node, msg))

    # ------------------------------------------------------------------ collect
    def collect(self) -> None:
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                t = node.type
                if t == "type_declaration":
                    for td in node.named_children:
                        if td.type == "type_definition":
                            name = src.node_text(td.named_children[0]).upper()
                            self.type_nodes[name] = (td, src)
                elif t in ("function_declaration", "function_block_declaration", "program_declaration"):
                    kind = t.replace("_declaration", "")
                    name = src.node_text(node.child_by_field_name("name") or node.named_children[0]).upper()
                    if name in self.pous and self.pous[name].node == node:
                        continue  # declared by the globals pre-pass
                    if name in self.pous:
                        self.diags.append(src.diag(node, f"duplicate POU '{name}'"))
                        continue
                    self.pous[name] = Pou(kind, name, node, src, pyname=f"{PY_PREFIX[kind]}_{name}")
                elif t == "configuration_declaration":
                    self.config = (node, src)
        for name in list(self.type_nodes):
            try:
                self.resolve_named(name)
            except _Err as e:
                self.diags.append(e.diag)
        for pou in self.pous.values():
            try:
                self.declare_pou(pou)
            except _Err as e:
                self.diags.append(e.diag)
                pou.failed = True

    # ------------------------------------------------------------------ types
    def resolve_named(self, name: str) -> Type:
        name = name.upper()
        if name in self.types:
            return self.types[name]
        if name in ELEMENTARY:
            return ELEMENTARY[name]
        if name in self.pous and self.pous[name].kind == "function_block":
            t = Type(name, "fb", pou=self.pous[name])
            self.types[name] = t
            return t
        if name in stdfbs.STANDARD_FBS:
            t = Type(name, "fb", pou=name)
            self.types[name] = t
            return t
        if name not in self.type_nodes:
            raise KeyError(name)
        td, src = self.type_nodes[name]
        spec = td.named_children[1]
        if spec.type in ("elementary_type", "identifier", "subrange_type"):
            if name in self._resolving:
                raise self.err(src, td, f"type '{name}' is defined in terms of itself")
            self._resolving.add(name)
            try:
                base = self.type_from_spec(spec, src, name)
            finally:
                self._resolving.discard(name)
            self.types[name] = base  # an alias / subrange is its base type for MatIEC's type rules
            return base
        t = Type(name, "pending")
        self.types[name] = t
        built = self.type_from_spec(spec, src, name)
        t.__dict__.update({k: v for k, v in built.__dict__.items()})
        for cands in self.enum_members.values():
            for i, c in enumerate(cands):
                if c is built:
                    cands[i] = t
        t.name = name
        init = self._type_init(td, src)
        if init is not None:
            t.init = init
        return t

    def _type_init(self, node: Node, src: ParsedSource):
        """Initialiser of a type definition or struct field (a node, or a blanked text)."""
        for off, text in src.type_initializers.items():
            if node.start_byte <= off <= node.end_byte + 2:
                return (text, src)
        kids = node.children
        for i, k in enumerate(kids):
            if k.type == ":=" and i + 1 < len(kids):
                return kids[i + 1]
        return None

    def type_from_spec(self, spec: Node, src: ParsedSource, name: str = "") -> Type:
        k = spec.type
        if k == "elementary_type":
            tname = src.node_text(spec).upper()
            if tname not in ELEMENTARY:
                raise self.err(src, spec, f"data type {tname} is not supported by MatIEC / the soft-PLC")
            return ELEMENTARY[tname]
        if k == "reference_type":
            target = self.type_from_spec(spec.named_children[-1], src)
            return Type(f"REF_TO {target.name}", "ref", elem=target)
        if k == "subrange_type":
            return self.type_from_spec(spec.named_children[0], src)
        if k == "identifier":
            tn = src.node_text(spec).upper()
            try:
                return self.resolve_named(tn)
            except KeyError:
                raise self.err(src, spec, f"unknown data type '{src.node_text(spec)}'") from None
        if k == "enumerated_type_inline":
            members = [src.node_text(e).upper() for e in spec.named_children]
            t = Type(name or "ENUM", "enum", 32, True, members=members)
            for m in members:
                self.enum_members.setdefault(m, []).append(t)
            return t
        if k == "structure_type_inline":
            t = Type(name or "STRUCT", "struct")
            for f in spec.named_children:
                if f.type != "structure_field":
                    continue
                fname = src.node_text(f.named_children[0]).lower()
                t.fields[fname] = self.type_from_spec(f.named_children[1], src)
                init = self._type_init(f, src)
                if init is not None:
                    t.field_inits[fname] = (init, src) if isinstance(init, Node) else init
            return t
        if k == "array_type":
            dims = []
            elem = None
            for c in spec.named_children:
                if c.type == "subrange":
                    lo, hi = (self.const_int(x, src) for x in c.named_children)
                    dims.append((lo, hi))
                else:
                    elem = self.type_from_spec(c, src)
            if elem is not None and elem.kind == "fb":
                raise self.err(src, spec, "arrays of function block instances are not supported by MatIEC")
            return Type("ARRAY", "array", elem=elem, dims=dims)
        if k == "string_type" or src.node_text(spec).upper().startswith("STRING"):
            return STRING
        raise self.err(src, spec, f"unsupported type specification '{src.node_text(spec)}'")

    def const_int(self, node: Node, src: ParsedSource) -> int:
        if node.type == "integer_literal":
            return self.int_literal(src.node_text(node))
        if node.type == "identifier":
            name = src.node_text(node).lower()
            g = self.globals.get(name)
            if g is not None and g.constant and g.init is not None:
                return self.const_int(g.init, g.src)
        if node.type == "unary_expression" and src.node_text(node.children[0]) == "-":
            return -self.const_int(node.named_children[-1], src)
        raise self.err(src, node, f"array bound '{src.node_text(node)}' is not a constant value")

    @staticmethod
    def int_literal(text: str) -> int:
        text = text.replace("_", "")
        sign = 1
        if text.startswith("-"):
            sign, text = -1, text[1:]
        elif text.startswith("+"):
            text = text[1:]
        if "#" in text:
            base, digits = text.split("#", 1)
            return sign * int(digits, int(base))
        return sign * int(text)

    # ------------------------------------------------------------------ declarations
    def declare_vars(self, block: Node, src: ParsedSource, into: dict[str, Var], order: list[str]) -> None:
        section = SECTION_OF.get(block.type, "var")
        qualifiers = " ".join(
            self_text.upper()
            for self_text in (src.node_text(c) for c in block.children if c.type == "var_qualifier_list")
        )
        constant = "CONSTANT" in qualifiers.split() or any(c.type == "CONSTANT" for c in block.children)
        for decl in block.named_children:
            if decl.type != "variable_declaration":
                continue
            names: list[str] = []
            location = None
            spec = None
            init: object = None
            state = "names"
            kids = decl.children
            for i, c in enumerate(kids):
                if state == "names":
                    if c.type == "identifier":
                        names.append(src.node_text(c))
                    elif c.type == "AT":
                        state = "at"
                    elif c.type == ":":
                        state = "type"
                elif state == "at":
                    if c.type == "direct_address":
                        location = src.node_text(c).upper()
                    elif c.type == ":":
                        state = "type"
                elif state == "type":
                    if c.is_named and c.type != "comment":
                        spec = c
                        state = "after"
                elif state == "after" and c.type == ":=":
                    nxt = kids[i + 1] if i + 1 < len(kids) else None
                    init = ("array", decl, i + 1) if nxt is not None and nxt.type == "[" else nxt
                    break
            if spec is None:
                raise self.err(src, decl, "variable declaration without a type")
            t = self.type_from_spec(spec, src)
            for written in names:
                n = written.lower()
                if n in into:
                    raise self.err(src, decl, f"duplicate variable '{written}'")
                into[n] = Var(n, t, section, init, location, constant, src, written)
                order.append(n)

    def declare_pou(self, pou: Pou) -> None:
        src = pou.src
        if pou.kind == "function":
            rt_node = pou.node.named_children[1]
            if rt_node.type in SECTION_OF or src.node_text(rt_node).upper() == "VOID":
                raise self.err(
                    src,
                    pou.node,
                    f"FUNCTION '{pou.name}' needs a return type (VOID functions "
                    "need iec2c -b, which OpenPLC does not pass)",
                )
            pou.ret = self.type_from_spec(rt_node, src)
        for block in pou.node.named_children:
            if block.type in SECTION_OF:
                self.declare_vars(block, src, pou.vars, pou.order)

    # ------------------------------------------------------------------ emit helpers
    def new_tmp(self) -> str:
        self.tmp += 1
        return f"_t{self.tmp}"

    # ------------------------------------------------------------------ expressions
    def ref_var(self, name: str, node: Node) -> tuple[str, Var]:
        pou = self.pou
        v = pou.vars.get(name) if pou else None
        if v is not None:
            if v.section == "ext":
                g = self.globals.get(name)
                if g is None:
                    raise self.err(
                        self.src, node, f"VAR_EXTERNAL '{name}' has no VAR_GLOBAL in the configuration"
                    )
                return f"G.v_{name}", v
            if self.mode == "function":
                return f"v_{name}", v
            return f"s.v_{name}", v
        if self.mode == "config" and name in self.globals:
            return f"G.v_{name}", self.globals[name]
        raise self.err(self.src, node, f"variable '{name}' is not declared in this scope")

    def lit_int(self, value: int, t: Type = ANY_INT) -> Ex:
        c = "i32" if -(1 << 31) <= value < (1 << 31) else "i64"
        if t.kind == "int":
            c = _c_of(t)
        return Ex(repr(value), t, c, value)

    def expr(self, node: Node, expected: Type | None = None) -> Ex:
        src = self.src
        k = node.type
        if k == "parenthesized_expression":
            inner = self.expr(node.named_children[0], expected)
            return Ex(f"({inner.code})", inner.t, inner.c, inner.const)
        if k == "integer_literal":
            return self.lit_int(self.int_literal(src.node_text(node)))
        if k == "real_literal":
            text = src.node_text(node).replace("_", "")
            value = float(text)
            return Ex(_py_float(value), ANY_REAL, "d", value)
        if k == "boolean_literal":
            value = src.node_text(node).upper() == "TRUE"
            return Ex(repr(value), BOOL, "bool", value)
        if k == "time_literal":
            ns = self.time_literal(src.node_text(node), node)
            return Ex(repr(ns), TIME, "time", ns)
        if k == "typed_literal":
            return self.typed_literal(node)
        if k in ("date_literal", "time_of_day_literal", "date_and_time_literal"):
            ns, tname = self.date_literal(src.node_text(node), node)
            return Ex(repr(ns), ELEMENTARY[tname], "time", ns)
        if k in ("string_literal", "character_string"):
            text = src.node_text(node)
            return Ex(
                repr(text[1:-1].replace("$$", "$").replace("$N", "\n").replace("$'", "'")), STRING, "str"
            )
        if k == "identifier":
            return self.identifier(node, expected)
        if k == "unary_expression":
            return self.unary(node)
        if k == "binary_expression":
            return self.binary(node)
        if k == "call_expression":
            return self.call(node, expected)
        if k == "dereference_expression":
            r = self.expr(node.named_children[0])
            if r.t.kind != "ref" or r.t.elem is None:
                raise self.err(src, node, f"'^' applied to a value of type {r.t.name}")
            return Ex(f"deref({r.code})", r.t.elem, _c_of(r.t.elem))
        if k == "member_access_expression":
            return self.member(node)
        if k == "index_expression":
            return self.index(node)
        raise self.err(src, node, f"unsupported expression '{src.node_text(node)[:40]}' ({k})")

    def identifier(self, node: Node, expected: Type | None) -> Ex:
        src = self.src
        if node.start_byte in src.enum_literals:
            tname, member = src.enum_literals[node.start_byte]
            try:
                et = self.resolve_named(tname)
            except KeyError:
                raise self.err(src, node, f"unknown enumerated type '{tname}'") from None
            if et.kind != "enum" or member.upper() not in et.members:
                raise self.err(src, node, f"'{member}' is not a value of '{tname}'")
            idx = et.members.index(member.upper())
            return Ex(repr(idx), et, "enum", idx)
        name = src.node_text(node).lower()
        pou = self.pou
        if pou is not None and name in pou.vars:
            code, v = self.ref_var(name, node)
            return Ex(code, v.type, _c_of(v.type))
        if pou is not None and pou.kind == "function" and name.upper() == pou.name:
            return Ex("v__ret", pou.ret, _c_of(pou.ret))
        if name == "null":
            return Ex("None", NULL_REF, "ref")
        cands = self.enum_members.get(name.upper())
        if cands:
            et = cands[0]
            if len(cands) > 1 and expected is not None and expected in cands:
                et = expected
            idx = et.members.index(name.upper())
            return Ex(repr(idx), et, "enum", idx)
        if self.mode == "config" and name in self.globals:
            v = self.globals[name]
            return Ex(f"G.v_{name}", v.type, _c_of(v.type))
        raise self.err(src, node, f"variable '{src.node_text(node)}' is not declared in this scope")

    def time_literal(self, text: str, node: Node) -> int:
        body = text.split("#", 1)[1].replace("_", "").lower()
        sign = 1
        if body.startswith("-"):
            sign, body = -1, body[1:]
        parts = {"d": 0.0, "h": 0.0, "m": 0.0, "s": 0.0, "ms": 0.0}
        extra_ns = 0
        for num, unit in re.findall(r"([0-9.]+(?:e[+-]?[0-9]+)?)(ms|us|ns|d|h|m|s)", body):
            if unit == "us":
                extra_ns += round(float(num) * 1000)
            elif unit == "ns":
                extra_ns += round(float(num))
            else:
                parts[unit] = float(num)
        if not re.fullmatch(r"([0-9.]+(?:e[+-]?[0-9]+)?(ms|us|ns|d|h|m|s))+", body):
            raise self.err(self.src, node, f"invalid TIME literal '{text}'")
        ns = rt.time_literal_ns(sign, parts["ms"], parts["s"], parts["m"], parts["h"], parts["d"])
        return ns + sign * extra_ns

    def date_literal(self, text: str, node: Node) -> tuple[int, str]:
        """D#, TOD#, DT# literals as nanoseconds since 1970-01-01 (MatIEC's timespec epoch)."""
        prefix, body = text.split("#", 1)
        prefix = prefix.upper()
        body = body.replace("_", "")
        try:
            if prefix in ("D", "DATE"):
                y, m, d = (int(x) for x in body.split("-"))
                return calendar.timegm((y, m, d, 0, 0, 0)) * rt.NS, "DATE"
            if prefix in ("TOD", "TIME_OF_DAY"):
                return self._tod_ns(body), "TIME_OF_DAY"
            y, m, d, tod = body.split("-", 3)
            return calendar.timegm((int(y), int(m), int(d), 0, 0, 0)) * rt.NS + self._tod_ns(
                tod
            ), "DATE_AND_TIME"
        except ValueError:
            raise self.err(self.src, node, f"invalid date/time literal '{text}'") from None

    @staticmethod
    def _tod_ns(body: str) -> int:
        h, m, sec = body.split(":")
        return rt.time_literal_ns(1, 0.0, float(sec), float(m), float(h), 0.0)

    def typed_literal(self, node: Node) -> Ex:
        src = self.src
        tname = src.node_text(node.named_children[0]).upper()
        val = node.named_children[-1]
        t = ELEMENTARY.get(tname)
        if t is None:
            raise self.err(src, node, f"unknown literal type '{tname}'")
        text = src.node_text(val)
        if t.kind == "int":
            if val.type == "boolean_literal":
                v = int(text.upper() == "TRUE")
            else:
                v = self.int_literal(text)
            lo, hi = _int_range(t)
            if not lo <= v <= hi:
                raise self.err(src, node, f"literal {text} out of range for {tname}")
            return Ex(repr(v), t, _c_of(t), v)
        if t.kind == "real":
            v = (
                float(self.int_literal(text))
                if val.type == "integer_literal"
                else float(text.replace("_", ""))
            )
            if t is REAL:
                v = rt.f32(v)
            return Ex(_py_float(v), t, _c_of(t), v)
        if t.kind == "bool":
            v = text.upper() in ("TRUE", "1")
            return Ex(repr(v), BOOL, "bool", v)
        if t.kind == "time":
            ns = self.time_literal("T#" + text, node)
            return Ex(repr(ns), TIME, "time", ns)
        raise self.err(src, node, f"unsupported typed literal '{src.node_text(node)}'")

    # C's usual arithmetic conversions on the classes of two operands
    @staticmethod
    def common_c(a: str, b: str) -> str:
        if "d" in (a, b):
            return "d"
        if "f" in (a, b):
            return "f"
        rank = {
            "i32": (32, 0),
            "u32": (32, 1),
            "i64": (64, 0),
            "u64": (64, 1),
            "bool": (32, 0),
            "enum": (32, 0),
        }
        ra, rb = rank.get(a, (32, 0)), rank.get(b, (32, 0))
        if ra[0] != rb[0]:
            best = ra if ra[0] > rb[0] else rb
        else:
            best = (ra[0], max(ra[1], rb[1]))
        return ("u" if best[1] else "i") + str(best[0])

    @staticmethod
    def to_c(e: Ex, c: str) -> str:
        if e.c == c or (c == "i32" and e.c in ("bool", "enum")):
            return e.code
        if c in ("f",):
            return f"f32({e.code})" if e.c not in ("f",) else e.code
        if c == "d":
            return f"float({e.code})" if e.c not in ("f", "d") else e.code
        if c == "u32":
            return f"wu32({e.code})"
        if c == "u64":
            return f"wu64({e.code})"
        if c == "i64" and e.c == "u64":
            return f"ws64({e.code})"
        if c == "i32" and e.c in ("u32", "i64", "u64"):
            return f"ws32({e.code})"
        return e.code

    def arith_type(self, a: Ex, b: Ex, op: str, node: Node) -> Type:
        ta, tb = a.t, b.t
        if ta.kind == "time" or tb.kind == "time":
            if ta.kind == "time" and tb.kind == "time" and op in "+-":
                return TIME
            if ta.kind == "time" and tb.is_num() and op in "*/":
                return TIME
            raise self.err(self.src, node, f"Data type mismatch for '{op}' expression")
        if not (ta.is_num() and tb.is_num()):
            raise self.err(self.src, node, f"Data type mismatch for '{op}' expression")
        if ta.kind in ("anyint", "anyreal") and tb.kind in ("anyint", "anyreal"):
            return ANY_REAL if ANY_REAL in (ta, tb) else ANY_INT
        if ta.kind in ("anyint", "anyreal"):
            ta, tb = tb, ta
            a, b = b, a
        # ta is typed now
        if tb.kind == "anyint":
            if ta.kind == "real":
                raise self.err(
                    self.src,
                    node,
                    f"Data type mismatch for '{op}' expression "
                    f"(integer literal with {ta.name}: write a real literal)",
                )
            return ta
        if tb.kind == "anyreal":
            if ta.kind == "int":
                raise self.err(
                    self.src,
                    node,
                    f"Data type mismatch for '{op}' expression ({ta.name} with a real literal)",
                )
            return ta
        if ta is not tb and ta.name != tb.name:
            raise self.err(
                self.src, node, f"Data type mismatch for '{op}' expression ({ta.name} {op} {tb.name})"
            )
        return ta

    def literal_c(self, lit: Ex, other: Ex) -> Ex:
        """An untyped integer literal takes the C class of its typed partner."""
        if lit.t.kind == "anyint" and other.t.kind == "int":
            return Ex(lit.code, other.t, _c_of(other.t), lit.const)
        return lit

    def binary(self, node: Node) -> Ex:
        src = self.src
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
            t = self.bit_type(a, b, op, node)
            a, b = self.literal_c(a, b), self.literal_c(b, a)
            c = self.common_c(a.c, b.c)
            return Ex(f"({self.to_c(a, c)} {BIT_OPS[op]} {self.to_c(b, c)})", t, c)
        if op in CMP_OPS:
            if a.t.kind == "ref" or b.t.kind == "ref":
                if op not in ("=", "<>") or a.t.kind != b.t.kind:
                    raise self.err(src, node, f"'{op}' is not defined for {_tn(a.t)} and {_tn(b.t)}")
                return Ex(f"({a.code} {'is' if op == '=' else 'is not'} {b.code})", BOOL, "bool")
            self.compare_types(a, b, op, node)
            a, b = self.literal_c(a, b), self.literal_c(b, a)
            if a.c in ("time", "str", "enum", "bool") or b.c in ("time", "str", "enum", "bool"):
                return Ex(f"({a.code} {CMP_OPS[op]} {b.code})", BOOL, "bool")
            c = self.common_c(a.c, b.c)
            return Ex(f"({self.to_c(a, c)} {CMP_OPS[op]} {self.to_c(b, c)})", BOOL, "bool")
        if op in ARITH_OPS:
            t = self.arith_type(a, b, op, node)
            if t.kind == "time":
                return self.time_arith(a, b, op)
            a, b = self.literal_c(a, b), self.literal_c(b, a)
            c = self.common_c(a.c, b.c)
            if a.const is not None and b.const is not None and t.kind in ("anyint", "anyreal"):
                return self.fold(a, b, op, t, node)
            x, y = self.to_c(a, c), self.to_c(b, c)
            if c in ("f", "d"):
                if op == "MOD":
                    raise self.err(src, node, "MOD needs integer operands")
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
        raise self.err(src, node, f"unsupported operator '{op}'")

    def fold(self, a: Ex, b: Ex, op: str, t: Type, node: Node) -> Ex:
        x, y = a.const, b.const
        if t.kind == "anyint":
            if op == "/":
                if y == 0:
                    raise self.err(self.src, node, "division by zero in a constant expression")
                v = rt.idiv(x, y)
            elif op == "MOD":
                v = rt.imod(x, y)
            else:
                v = {"+": x + y, "-": x - y, "*": x * y}[op]
            return self.lit_int(v)
        x, y = float(x), float(y)
        v = rt.fdiv(x, y) if op == "/" else {"+": x + y, "-": x - y, "*": x * y}[op]
        return Ex(_py_float(v), ANY_REAL, "d", v)

    def time_arith(self, a: Ex, b: Ex, op: str) -> Ex:
        if op == "+":
            return Ex(f"({a.code} + {b.code})", TIME, "time")
        if op == "-":
            return Ex(f"({a.code} - {b.code})", TIME, "time")
        fn = "time_mul" if op == "*" else "time_div"
        return Ex(f"{fn}({a.code}, {b.code})", TIME, "time")

    def bit_type(self, a: Ex, b: Ex, op: str, node: Node) -> Type:
        if a.t.kind in ("int", "anyint") and b.t.kind in ("int", "anyint"):
            if a.t.kind == "int" and b.t.kind == "int" and a.t.name != b.t.name:
                raise self.err(
                    self.src, node, f"Data type mismatch for '{op}' expression ({a.t.name}, {b.t.name})"
                )
            return a.t if a.t.kind == "int" else b.t
        raise self.err(self.src, node, f"Data type mismatch for '{op}' expression ({a.t.name}, {b.t.name})")

    def compare_types(self, a: Ex, b: Ex, op: str, node: Node) -> None:
        ta, tb = a.t, b.t
        if ta.kind in ("anyint", "anyreal") or tb.kind in ("anyint", "anyreal"):
            typed = tb if ta.kind in ("anyint", "anyreal") else ta
            lit = ta if typed is tb else tb
            if typed.kind in ("int", "anyint") and lit.kind == "anyint":
                return
            if (
                typed.kind in ("real", "anyreal", "anyint")
                and lit.kind in ("anyreal", "anyint")
                and not (typed.kind == "real" and lit.kind == "anyint")
            ):
                return
            if typed.kind == "int" and lit.kind == "anyreal":
                raise self.err(
                    self.src, node, f"Data type mismatch for '{op}' expression ({typed.name}, real literal)"
                )
            if typed.kind == "real" and lit.kind == "anyint":
                raise self.err(
                    self.src,
                    node,
                    f"Data type mismatch for '{op}' expression ({typed.name}, integer literal)",
                )
            return
        if ta.name != tb.name and not (ta.kind == tb.kind == "time"):
            raise self.err(self.src, node, f"Data type mismatch for '{op}' expression ({ta.name}, {tb.name})")

    def unary(self, node: Node) -> Ex:
        op = self.src.node_text(node.children[0]).upper()
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
            raise self.err(self.src, node, f"NOT is not defined for {a.t.name}")
        if op == "-":
            if a.const is not None and a.t.kind in ("anyint", "anyreal"):
                if a.t.kind == "anyint":
                    return self.lit_int(-a.const)
                return Ex(_py_float(-a.const), ANY_REAL, "d", -a.const)
            if a.c in ("f", "d"):
                return Ex(f"(-{a.code})", a.t, a.c)
            if a.t.kind == "time":
                return Ex(f"(-{a.code})", TIME, "time")
            if a.t.kind in ("int", "anyint"):
                wrap = {"i32": "ws32", "u32": "wu32", "i64": "ws64", "u64": "wu64"}.get(a.c, "ws32")
                return Ex(f"{wrap}(-{a.code})", a.t, a.c)
            raise self.err(self.src, node, f"unary '-' is not defined for {a.t.name}")
        if op == "+":
            return a
        raise self.err(self.src, node, f"unsupported unary operator '{op}'")

    # ------------------------------------------------------------------ access paths
    def fb_members(self, t: Type) -> dict[str, tuple[Type, str]]:
        if isinstance(t.pou, str):
            _, members = stdfbs.STANDARD_FBS[t.pou]
            return {k: (ELEMENTARY[v[0]], v[1]) for k, v in members.items()}
        pou: Pou = t.pou
        return {n: (v.type, v.section) for n, v in pou.vars.items()}

    def member(self, node: Node) -> Ex:
        base = self.expr(node.named_children[0])
        fname = self.src.node_text(node.named_children[-1]).lower()
        t = base.t
        if t.kind == "struct":
            if fname not in t.fields:
                raise self.err(self.src, node, f"'{t.name}' has no field '{fname}'")
            ft = t.fields[fname]
            return Ex(f"{base.code}.v_{fname}", ft, _c_of(ft))
        if t.kind == "fb":
            members = self.fb_members(t)
            if fname not in members:
                raise self.err(self.src, node, f"function block '{t.name}' has no variable '{fname}'")
            ft, section = members[fname]
            if section not in ("in", "out", "inout"):
                raise self.err(
                    self.src,
                    node,
                    f"'{fname}' is internal to '{t.name}' (only inputs and outputs are accessible)",
                )
            return Ex(f"{base.code}.v_{fname}", ft, _c_of(ft))
        raise self.err(self.src, node, f"'.{fname}' applied to a value of type {t.name}")

    def index(self, node: Node) -> Ex:
        base = self.expr(node.named_children[0])
        t = base.t
        if t.kind != "array":
            raise self.err(self.src, node, f"indexing a value of type {t.name}")
        idx_nodes = node.named_children[1:]
        if len(idx_nodes) != len(t.dims):
            raise self.err(
                self.src, node, f"array has {len(t.dims)} dimension(s), {len(idx_nodes)} index(es) given"
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
                raise self.err(self.src, inode, f"array index must be an integer, not {ie.t.name}")
            n = hi - lo + 1
            if ie.const is not None:
                if not lo <= ie.const <= hi:
                    raise self.err(self.src, inode, f"array index {ie.const} out of range [{lo}..{hi}]")
                k = (ie.const - lo) * st
                parts.append(repr(k))
            else:
                k = f"ix({ie.code}, {lo}, {n})"
                parts.append(k if st == 1 else f"{k} * {st}")
        flat = " + ".join(parts) if parts else "0"
        return Ex(f"{base.code}[{flat}]", t.elem, _c_of(t.elem))

    # ------------------------------------------------------------------ store (assignment rules)
    def convert_store(self, e: Ex, dst: Type, node: Node, what: str = "':='") -> str:
        """Code that stores expression e into a variable of type dst, with MatIEC's type rules."""
        src_t = e.t
        if dst.kind == "int":
            if src_t.kind == "anyint":
                if e.const is not None:
                    return repr(rt.WRAP[(dst.bits, dst.signed)](e.const))
                return f"w{'s' if dst.signed else 'u'}{dst.bits}({e.code})"
            if src_t.kind == "int" and src_t.name == dst.name:
                wrap = f"w{'s' if dst.signed else 'u'}{dst.bits}"
                if not self._needs_wrap(e) or e.code.startswith(wrap + "("):
                    return e.code
                return f"{wrap}({e.code})"
            raise self.err(
                self.src,
                node,
                f"Incompatible data types for {what} operation "
                f"({_tn(src_t)} to {dst.name}: use an explicit conversion)",
            )
        if dst.kind == "real":
            if src_t.kind == "anyreal" or (src_t.kind == "real" and src_t.name == dst.name):
                if dst is REAL and e.c != "f":
                    if e.const is not None:
                        return _py_float(rt.f32(float(e.const)))
                    return f"f32({e.code})"
                return e.code
            raise self.err(
                self.src,
                node,
                f"Incompatible data types for {what} operation "
                f"({_tn(src_t)} to {dst.name}"
                + (
                    ": write a real literal such as 1.0)"
                    if src_t.kind == "anyint"
                    else ": use an explicit conversion)"
                ),
            )
        if dst.kind == "bool":
            if src_t.kind == "bool":
                return e.code
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to BOOL)"
            )
        if dst.kind == "time":
            if src_t.kind == "time":
                return e.code
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to TIME)"
            )
        if dst.kind == "enum":
            if src_t is dst or (src_t.kind == "enum" and src_t.name == dst.name):
                return e.code
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to {dst.name})"
            )
        if dst.kind in ("struct", "fb"):
            if src_t.kind == dst.kind and src_t.name == dst.name:
                return f"{e.code}._copy()"
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to {dst.name})"
            )
        if dst.kind == "array":
            if src_t.kind == "array" and self.same_array(src_t, dst):
                return f"copy_array({e.code})"
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation (array shapes differ)"
            )
        if dst.kind == "ref":
            if src_t.kind == "ref" and (src_t.elem is None or src_t.elem.name == dst.elem.name):
                return e.code
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to {dst.name})"
            )
        if dst.kind == "string":
            if src_t.kind == "string":
                return e.code
            raise self.err(
                self.src, node, f"Incompatible data types for {what} operation ({_tn(src_t)} to STRING)"
            )
        raise self.err(self.src, node, f"cannot assign to a value of type {dst.name}")

    @staticmethod
    def _needs_wrap(e: Ex) -> bool:
        return not re.fullmatch(r"[A-Za-z_][\w.]*(\[[^\]]*\])?", e.code)

    @staticmethod
    def same_array(a: Type, b: Type) -> bool:
        return (
            a.dims == b.dims
            and a.elem is not None
            and b.elem is not None
            and (a.elem is b.elem or a.elem.name == b.elem.name)
        )

    # ------------------------------------------------------------------ calls
    def call_args(self, node: Node) -> tuple[list[Node], dict[str, tuple[Node, str]]]:
        arglist = node.named_children[-1]
        positional: list[Node] = []
        named: dict[str, tuple[Node, str]] = {}
        for a in arglist.named_children:
            if a.type == "named_argument":
                kids = a.children
                pname = self.src.node_text(kids[0]).lower()
                arrow = self.src.node_text(kids[1])
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
            raise self.err(self.src, node, "only named functions can be called in an expression")
        name = self.src.node_text(fname_node).upper()
        positional, named = self.call_args(node)
        if name in self.pous and self.pous[name].kind == "function":
            return self.user_call(self.pous[name], positional, named, node)
        if self.pou is not None and name.lower() in self.pou.vars:
            raise self.err(
                self.src, node, "function block instances are called as statements, not in expressions"
            )
        if named and name not in self.pous:
            # standard functions called with formal names (IN1 := ...) map to their positions
            order = sorted(named)
            positional = positional + [named[k][0] for k in order]
        args = [self.expr(a) for a in positional]
        if name == "REF":
            if len(positional) != 1:
                raise self.err(self.src, node, "REF takes one variable")
            target = self.lvalue(positional[0])
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
            raise self.err(self.src, node, f"unknown conversion function {frm}_TO_{to}")
        x = self.convert_store(a, src_t, node, what=f"{frm}_TO_{to} argument")
        if dst.kind == "int":
            wrap = f"w{'s' if dst.signed else 'u'}{dst.bits}"
            if src_t.kind in ("int", "bool"):
                return Ex(f"{wrap}(int({x}))" if src_t.kind == "bool" else f"{wrap}({x})", dst, _c_of(dst))
            if src_t.kind == "real":
                fn = "real_to_sint" if dst.signed else "real_to_uint"
                return Ex(f"{wrap}({fn}({x}))", dst, _c_of(dst))
            if src_t.kind == "time":
                return Ex(f"{wrap}(time_to_int({x}))", dst, _c_of(dst))
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
                return Ex(f"f32({core})" if dst is REAL else core, dst, _c_of(dst))
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
        raise self.err(self.src, node, f"conversion {frm}_TO_{to} is not supported")

    def common_arg_type(self, args: list[Ex], node: Node, name: str) -> Type:
        typed = [a.t for a in args if a.t.kind not in ("anyint", "anyreal")]
        if not typed:
            return ANY_REAL if any(a.t.kind == "anyreal" for a in args) else ANY_INT
        t = typed[0]
        for o in typed[1:]:
            if o.name != t.name:
                raise self.err(self.src, node, f"{name}: arguments of different types ({t.name}, {o.name})")
        return t

    def as_type(self, a: Ex, t: Type, node: Node, name: str) -> str:
        if t.kind in ("anyint", "anyreal"):
            return a.code
        return self.convert_store(a, t, node, what=f"{name} argument")

    def std_call(self, name: str, args: list[Ex], node: Node) -> Ex:
        n = len(args)

        def need(k: int) -> None:
            if n != k:
                raise self.err(self.src, node, f"{name} takes {k} argument(s), {n} given")

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
                raise self.err(self.src, node, f"ABS is not defined for {a.t.name}")
            if a.t.kind not in ("real", "anyreal"):
                raise self.err(self.src, node, f"{name} needs a REAL or LREAL argument, not {a.t.name}")
            core = f"{MATH_FUNCS[name]}({a.code})"
            return Ex(f"f32({core})" if a.t is REAL else core, a.t, "f" if a.t is REAL else "d")
        if name == "EXPT":
            need(2)
            a, b = args
            if a.t.kind not in ("real", "anyreal"):
                raise self.err(self.src, node, f"EXPT needs a REAL or LREAL base, not {a.t.name}")
            if not b.t.is_num():
                raise self.err(self.src, node, "EXPT exponent must be numeric")
            core = f"expt({a.code}, {b.code})"
            return Ex(f"f32({core})" if a.t is REAL else core, a.t, "f" if a.t is REAL else "d")
        if name in ("MIN", "MAX"):
            if n < 2:
                raise self.err(self.src, node, f"{name} needs at least 2 arguments")
            t = self.common_arg_type(args, node, name)
            codes = [self.as_type(a, t, node, name) for a in args]
            return Ex(
                f"{name.lower()}({', '.join(codes)})",
                t,
                _c_of(t) if t.kind not in ("anyint", "anyreal") else args[0].c,
            )
        if name == "LIMIT":
            need(3)
            t = self.common_arg_type(args, node, name)
            codes = [self.as_type(a, t, node, name) for a in args]
            c = _c_of(t) if t.kind not in ("anyint", "anyreal") else ("d" if t.kind == "anyreal" else "i32")
            return Ex(f"limit({', '.join(codes)})", t, c)
        if name == "SEL":
            need(3)
            g = args[0]
            if g.t.kind != "bool":
                raise self.err(self.src, node, "SEL selector must be BOOL")
            t = self.common_arg_type(args[1:], node, name)
            a, b = (self.as_type(x, t, node, name) for x in args[1:])
            c = _c_of(t) if t.kind not in ("anyint", "anyreal") else args[1].c
            return Ex(f"({b} if {g.code} else {a})", t, c)
        if name == "MUX":
            if n < 2:
                raise self.err(self.src, node, "MUX needs a selector and at least one input")
            k = args[0]
            if k.t.kind not in ("int", "anyint"):
                raise self.err(self.src, node, "MUX selector must be an integer")
            t = self.common_arg_type(args[1:], node, name)
            codes = [self.as_type(x, t, node, name) for x in args[1:]]
            c = _c_of(t) if t.kind not in ("anyint", "anyreal") else args[1].c
            return Ex(f"mux({k.code}, {', '.join(codes)})", t, c)
        if name in ("SHL", "SHR", "ROL", "ROR"):
            need(2)
            a, b = args
            if a.t.kind != "int":
                raise self.err(self.src, node, f"{name} needs a typed bit-string/integer first argument")
            return Ex(f"{name.lower()}({a.code}, {b.code}, {a.t.bits})", a.t, _c_of(a.t))
        if name == "TRUNC":
            need(1)
            a = args[0]
            if a.t.kind not in ("real", "anyreal"):
                raise self.err(self.src, node, "TRUNC needs a REAL or LREAL argument")
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
        raise self.err(self.src, node, f"unknown function '{name}'")

    def lvalue(self, node: Node) -> Ex:
        if node.type not in ("identifier", "member_access_expression", "index_expression"):
            raise self.err(self.src, node, "a variable is required here")
        e = self.expr(node)
        if e.const is not None:
            raise self.err(self.src, node, "cannot assign to a constant")
        return e

    def user_call(
        self, pou: Pou, positional: list[Node], named: dict, node: Node, statement: bool = False
    ) -> Ex:
        params = pou.params()
        if not params and not statement:
            raise self.err(
                self.src,
                node,
                f"no parameter defined in function invocation of '{pou.name}' "
                "(MatIEC needs at least one input)",
            )
        if len(positional) > len(params):
            raise self.err(self.src, node, f"too many arguments for '{pou.name}'")
        bound: dict[str, Node] = {}
        for p, a in zip(params, positional, strict=False):
            bound[p.name] = a
        outs: list[tuple[str, Node]] = []
        for pname, (value, kind) in named.items():
            if kind.startswith("=>"):
                if pname not in pou.vars or pou.vars[pname].section != "out":
                    raise self.err(self.src, node, f"'{pname}' is not an output of '{pou.name}'")
                outs.append((pname, value))
            else:
                if pname not in pou.vars or pou.vars[pname].section not in ("in", "inout"):
                    raise self.err(self.src, node, f"'{pname}' is not an input of '{pou.name}'")
                bound[pname] = value
        codes = []
        writeback: list[tuple[int, Ex, Var]] = []
        for p in params:
            if p.name not in bound:
                if p.section == "inout":
                    raise self.err(self.src, node, f"VAR_IN_OUT '{p.name}' of '{pou.name}' must be given")
                codes.append("None")
                continue
            a = bound[p.name]
            if p.section == "inout":
                lv = self.lvalue(a)
                if lv.t.name != p.type.name and not (lv.t.kind == "array" and self.same_array(lv.t, p.type)):
                    raise self.err(self.src, a, f"VAR_IN_OUT '{p.name}' needs {p.type.name}, got {lv.t.name}")
                codes.append(lv.code)
                if p.type.kind not in ("struct", "array", "fb"):
                    writeback.append((0, lv, p))
            else:
                codes.append(self.convert_store(self.expr(a, p.type), p.type, a, what=f"'{p.name}' argument"))
        call = f"{pou.pyname}({', '.join(codes)})"
        if not pou.outputs() and not any(
            p.section == "inout" and p.type.kind not in ("struct", "array", "fb") for p in params
        ):
            return Ex(call, pou.ret, _c_of(pou.ret))
        tmp = self.new_tmp()
        self.pre.append(f"{tmp} = {call}")
        out_index = {v.name: i + 1 for i, v in enumerate(pou.outputs())}
        base = 1 + len(pou.outputs())
        scalar_inouts = [
            p for p in params if p.section == "inout" and p.type.kind not in ("struct", "array", "fb")
        ]
        for pname, target in outs:
            if target is None:
                continue
            lv = self.lvalue(target)
            ov = pou.vars[pname]
            val = Ex(f"{tmp}[{out_index[pname]}]", ov.type, _c_of(ov.type))
            self.pre.append(f"{lv.code} = {self.convert_store(val, lv.t, target)}")
        for i, p in enumerate(scalar_inouts):
            lv = next(w[1] for w in writeback if w[2] is p)
            self.pre.append(f"{lv.code} = {tmp}[{base + i}]")
        return Ex(f"{tmp}[0]", pou.ret, _c_of(pou.ret))

    # ------------------------------------------------------------------ statements
    def emit(self, line: str) -> None:
        self.out.append("    " * self.indent + line)

    def flush_pre(self) -> None:
        for p in self.pre:
            self.emit(p)
        self.pre = []

    def body(self, nodes: list[Node]) -> None:
        start = len(self.out)
        for st in nodes:
            try:
                self.statement(st)
            except _Err as e:
                self.diags.append(e.diag)
                self.pre = []
        if len(self.out) == start:
            self.emit("pass")

    def cond(self, node: Node) -> str:
        e = self.expr(node)
        if e.t.kind != "bool":
            raise self.err(self.src, node, f"condition must be BOOL, not {e.t.name}")
        return e.code

    def statement(self, st: Node) -> None:
        k = st.type
        src = self.src
        if k in ("empty_statement", "comment"):
            return
        if k == "assignment_statement":
            target = st.named_children[0]
            value = st.named_children[-1]
            lv = self.lvalue(target)
            e = self.expr(value, lv.t)
            code = self.convert_store(e, lv.t, st)
            self.flush_pre()
            self.emit(f"{lv.code} = {code}")
            return
        if k == "invocation_statement":
            self.invocation(st.named_children[0])
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
            self.emit("while True:")
            self.indent += 1
            c = self.cond(kids[0])
            self.flush_pre()
            self.emit(f"if not {c}:")
            self.emit("    break")
            self.loop_depth += 1
            self.body(kids[1:])
            self.loop_depth -= 1
            self.indent -= 1
            return
        if k == "repeat_statement":
            kids = [c for c in st.named_children if c.type != "comment"]
            flag = self.new_tmp()
            cond_node = kids[-1]
            self.emit(f"{flag} = True")
            c = self.cond(cond_node)
            if self.pre:
                raise self.err(src, cond_node, "UNTIL condition with function outputs is not supported")
            self.emit(f"while {flag} or not {c}:")
            self.indent += 1
            self.emit(f"{flag} = False")
            self.loop_depth += 1
            self.body(kids[:-1])
            self.loop_depth -= 1
            self.indent -= 1
            return
        if k == "exit_statement":
            if not self.loop_depth:
                raise self.err(src, st, "EXIT outside a loop")
            self.emit("break")
            return
        if k == "continue_statement":
            if not self.loop_depth:
                raise self.err(src, st, "CONTINUE outside a loop")
            self.emit("continue")
            return
        if k == "return_statement":
            self.emit(self.return_code)
            return
        raise self.err(src, st, f"unsupported statement '{src.node_text(st)[:40]}' ({k})")

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
                    self.flush_pre()
                    self.emit(f"if {c_code}:")
                elif self.pre:
                    self.emit("else:")
                    self.indent += 1
                    depth += 1
                    self.flush_pre()
                    self.emit(f"if {c_code}:")
                else:
                    self.emit(f"elif {c_code}:")
                first = False
                self.indent += 1
                self.body(stmts)
                self.indent -= 1
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
                self.emit("else:")
                self.indent += 1
                self.body(stmts)
                self.indent -= 1
            else:
                i += 1
        self.indent -= depth

    def case_statement(self, st: Node) -> None:
        kids = [c for c in st.named_children if c.type != "comment"]
        sel = self.expr(kids[0])
        tmp = self.new_tmp()
        if sel.t.kind == "int":
            code = f"w{'s' if sel.t.signed else 'u'}{sel.t.bits}({sel.code})"
        else:
            code = sel.code
        self.flush_pre()
        self.emit(f"{tmp} = {code}")
        first = True
        for clause in kids[1:]:
            if clause.type == "case_clause":
                conds = []
                stmts = []
                for c in clause.named_children:
                    if c.type == "case_value":
                        v = c.named_children[0]
                        if v.type == "subrange":
                            lo, hi = (self.expr(x, sel.t) for x in v.named_children)
                            conds.append(f"{lo.code} <= {tmp} <= {hi.code}")
                        else:
                            e = self.expr(v, sel.t if sel.t.kind == "enum" else None)
                            if sel.t.kind == "enum" and e.t is not sel.t and v.type == "identifier":
                                raise self.err(
                                    self.src, v, f"'{self.src.node_text(v)}' is not a value of {sel.t.name}"
                                )
                            conds.append(f"{tmp} == {e.code}")
                    elif c.type != "comment":
                        stmts.append(c)
                self.emit(f"{'if' if first else 'elif'} {' or '.join(conds) or 'False'}:")
                first = False
                self.indent += 1
                self.body(stmts)
                self.indent -= 1
            elif clause.type == "else_clause":
                stmts = [x for x in clause.named_children if x.type != "comment"]
                if first:
                    self.emit("if True:")
                else:
                    self.emit("else:")
                first = False
                self.indent += 1
                self.body(stmts)
                self.indent -= 1

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
        lv = self.lvalue(var_node)
        if lv.t.kind != "int":
            raise self.err(self.src, var_node, "FOR variable must be an integer variable")
        start = self.convert_store(self.expr(start_node), lv.t, start_node)
        end = self.expr(end_node)
        self.convert_store(end, lv.t, end_node)
        step = self.expr(step_node) if step_node is not None else self.lit_int(1)
        self.convert_store(step, lv.t, step_node or st)
        wrap = f"w{'s' if lv.t.signed else 'u'}{lv.t.bits}"
        flag = self.new_tmp()
        self.flush_pre()
        self.emit(f"{lv.code} = {start}")
        self.emit(f"{flag} = True")
        self.emit("while True:")
        self.indent += 1
        self.emit(f"if not {flag}:")
        self.emit(f"    {lv.code} = {wrap}({lv.code} + {step.code})")
        self.emit(f"{flag} = False")
        if step.const is not None:
            cmp = "<=" if step.const > 0 else ">="
            self.emit(f"if not ({lv.code} {cmp} {end.code}):")
        else:
            self.emit(
                f"if not (({lv.code} <= {end.code}) if {step.code} > 0 else ({lv.code} >= {end.code})):"
            )
        self.emit("    break")
        self.loop_depth += 1
        self.body(stmts)
        self.loop_depth -= 1
        self.indent -= 1

    def invocation(self, call: Node) -> None:
        target = call.named_children[0]
        positional, named = self.call_args(call)
        if target.type == "identifier":
            name = self.src.node_text(target).upper()
            if (
                name in self.pous
                and self.pous[name].kind == "function"
                and (self.pou is None or name.lower() not in self.pou.vars)
            ):
                e = self.user_call(self.pous[name], positional, named, call, statement=True)
                self.flush_pre()
                if not e.code.startswith("_t"):
                    self.emit(e.code)
                return
        fb = self.expr(target)
        if fb.t.kind != "fb":
            raise self.err(self.src, call, f"'{self.src.node_text(target)}' is not a function block instance")
        members = self.fb_members(fb.t)
        inputs = [n for n, (_, sec) in members.items() if sec in ("in", "inout")]
        if len(positional) > len(inputs):
            raise self.err(self.src, call, "too many positional arguments in function block call")
        assigns = list(zip(inputs, positional, strict=False))
        outs = []
        for pname, (value, kind) in named.items():
            if pname not in members:
                raise self.err(self.src, call, f"function block '{fb.t.name}' has no variable '{pname}'")
            if kind.startswith("=>"):
                outs.append((pname, value))
            else:
                assigns.append((pname, value))
        lines = []
        inouts_back = []
        for pname, value in assigns:
            mt, sec = members[pname]
            if sec not in ("in", "inout"):
                raise self.err(self.src, call, f"'{pname}' is not an input of '{fb.t.name}'")
            if sec == "inout":
                lv = self.lvalue(value)
                lines.append(f"{fb.code}.v_{pname} = {lv.code}")
                if mt.kind not in ("struct", "array", "fb"):
                    inouts_back.append(f"{lv.code} = {fb.code}.v_{pname}")
            else:
                e = self.expr(value, mt)
                lines.append(f"{fb.code}.v_{pname} = {self.convert_store(e, mt, value, what=repr(pname))}")
        self.flush_pre()
        for ln in lines:
            self.emit(ln)
        self.emit(f"{fb.code}._run()")
        for ln in inouts_back:
            self.emit(ln)
        for pname, target_node in outs:
            mt, sec = members[pname]
            lv = self.lvalue(target_node)
            val = Ex(f"{fb.code}.v_{pname}", mt, _c_of(mt))
            self.emit(f"{lv.code} = {self.convert_store(val, lv.t, target_node)}")

    # ------------------------------------------------------------------ initial values
    def default_code(self, t: Type) -> str:
        k = t.kind
        if k in ("int", "enum"):
            return "0"
        if k == "real":
            return "0.0"
        if k == "bool":
            return "False"
        if k == "time":
            return "0"
        if k == "string":
            return "''"
        if k == "ref":
            return "None"
        if k == "struct":
            return f"{self.struct_class(t)}()"
        if k == "fb":
            if isinstance(t.pou, str):
                return f"{t.pou}(CLK)"
            return f"{t.pou.pyname}()"
        if k == "array":
            if t.init is not None:
                return self.init_code(t, t.init)
            elem = self.default_code(t.elem)
            if t.elem.kind in ("struct", "fb", "array"):
                return f"[{elem} for _ in range({t.size})]"
            return f"[{elem}] * {t.size}"
        raise ValueError(k)

    def init_code(self, t: Type, init) -> str:
        if init is None:
            return self.default_code(t)
        if isinstance(init, tuple) and len(init) == 2 and isinstance(init[0], str):
            node, src = self.snippet_initializer(init[0], init[1])
            return self.with_src(src, lambda: self.init_code(t, node))
        if isinstance(init, tuple) and len(init) == 2:  # (node, src)
            return self.with_src(init[1], lambda: self.init_code(t, init[0]))
        if isinstance(init, tuple) and init[0] == "array":
            _, decl, start = init
            items = []
            for c in decl.children[start + 1 :]:
                if c.type == "]":
                    break
                if c.is_named and c.type != "comment":
                    items.append(c)
            return self.array_init(t, items, decl)
        node: Node = init
        if node.type == "structure_initializer":
            return self.struct_init(t, node)
        if t.kind == "array":
            return self.array_init(t, [node], node)
        saved = (self.pou, self.mode)
        self.pou, self.mode = None, "config"
        try:
            e = self.expr(node, t)
            return self.convert_store(e, t, node, what="initial value")
        finally:
            self.pou, self.mode = saved

    def with_src(self, src: ParsedSource, fn):
        saved = self.src
        self.src = src
        try:
            return fn()
        finally:
            self.src = saved

    def snippet_initializer(self, text: str, origin: ParsedSource) -> tuple[Node, ParsedSource]:
        snippet = f"PROGRAM SNIPPET\nVAR\n  x : INT := {text};\nEND_VAR\nx := 0;\nEND_PROGRAM\n"
        src = parse_source(snippet, origin.filename)
        decl = src.tree.root_node.named_children[0].named_children[1].named_children[0]
        kids = decl.children
        i = next(i for i, c in enumerate(kids) if c.type == ":=")
        nxt = kids[i + 1]
        if nxt.type == "[":
            return ("array", decl, i + 1), src
        return nxt, src

    def struct_init(self, t: Type, node: Node) -> str:
        parts = []
        for f in node.named_children:
            if f.type != "structure_initializer_field":
                continue
            fname = self.src.node_text(f.named_children[0]).lower()
            value = f.named_children[-1]
            if t.kind == "struct":
                if fname not in t.fields:
                    raise self.err(self.src, f, f"'{t.name}' has no field '{fname}'")
                ft = t.fields[fname]
            elif t.kind == "fb":
                members = self.fb_members(t)
                if fname not in members:
                    raise self.err(self.src, f, f"'{t.name}' has no variable '{fname}'")
                ft = members[fname][0]
            else:
                raise self.err(self.src, node, f"structure initialiser for a value of type {t.name}")
            parts.append(f"v_{fname}={self.init_code(ft, value)}")
        return f"mk({self.default_code(t)}, {', '.join(parts)})"

    def array_init(self, t: Type, items: list[Node], where: Node) -> str:
        if t.kind != "array":
            raise self.err(self.src, where, f"array initialiser for a value of type {t.name}")
        codes: list[str] = []
        for it in items:
            if it.type == "array_repetition":
                count = self.const_int(it.named_children[0], self.src)
                val = it.named_children[1] if len(it.named_children) > 1 else None
                code = self.init_code(t.elem, val) if val is not None else self.default_code(t.elem)
                codes.extend([code] * count)
            elif it.type == "structure_initializer":
                codes.append(self.struct_init(t.elem, it))
            else:
                codes.append(self.init_code(t.elem, it))
        if len(codes) > t.size:
            raise self.err(
                self.src, where, f"array initialiser has {len(codes)} values for {t.size} elements"
            )
        rest = t.size - len(codes)
        if rest:
            codes.extend([self.default_code(t.elem)] * rest)
        return f"[{', '.join(codes)}]"

    # ------------------------------------------------------------------ classes
    def struct_class(self, t: Type) -> str:
        name = f"S_{t.name}" if t.name not in ("STRUCT",) else f"S_anon{id(t)}"
        if name not in self.struct_done:
            self.struct_done.add(name)
            self.struct_pending.append((name, t))
        return name

    def gen_structs(self) -> list[str]:
        lines: list[str] = []
        while self.struct_pending:
            name, t = self.struct_pending.pop(0)
            slots = ", ".join(repr(f"v_{f}") for f in t.fields)
            lines.append(f"class {name}:")
            lines.append(f"    __slots__ = ({slots}{',' if len(t.fields) == 1 else ''})")
            lines.append("    def __init__(self):")
            for f, ft in t.fields.items():
                init = t.field_inits.get(f)
                try:
                    lines.append(f"        self.v_{f} = {self.init_code(ft, init)}")
                except _Err as e:
                    self.diags.append(e.diag)
                    lines.append(f"        self.v_{f} = {self.default_code(ft)}")
            if not t.fields:
                lines.append("        pass")
            lines.append("    def _copy(self):")
            lines.append(f"        n = {name}.__new__({name})")
            for f, ft in t.fields.items():
                lines.append(f"        n.v_{f} = {self.copy_code(ft, f'self.v_{f}')}")
            lines.append("        return n")
            lines.append("")
        return lines

    @staticmethod
    def copy_code(t: Type, code: str) -> str:
        if t.kind in ("struct", "fb"):
            return f"{code}._copy()"
        if t.kind == "array":
            return f"copy_array({code})"
        return code

    def gen_pou(self, pou: Pou) -> None:
        self.pou = pou
        self.src = pou.src
        self.tmp = 0
        self.pre = []
        self.loop_depth = 0
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
        self.mode = "method"
        names = [n for n in pou.order if pou.vars[n].section != "ext"]
        slots = ", ".join(repr(f"v_{n}") for n in names)
        self.indent = 0
        self.emit(f"class {pou.pyname}:")
        self.indent = 1
        self.emit(f"__slots__ = ({slots}{',' if len(names) == 1 else ''})")
        self.emit("def __init__(self):")
        self.indent = 2
        self.emit("s = self")
        for n in names:
            v = pou.vars[n]
            try:
                self.emit(f"s.v_{n} = {self.init_code(v.type, v.init)}")
            except _Err as e:
                self.diags.append(e.diag)
        self.emit("pass")
        self.indent = 1
        self.emit("def _copy(self):")
        self.emit(f"    n = {pou.pyname}.__new__({pou.pyname})")
        for n in names:
            self.emit(f"    n.v_{n} = {self.copy_code(pou.vars[n].type, f'self.v_{n}')}")
        self.emit("    return n")
        self.emit("def _run(self):")
        self.indent = 2
        self.emit("s = self")
        for n in names:
            v = pou.vars[n]
            if v.section == "temp":
                self.emit(f"s.v_{n} = {self.init_code(v.type, v.init)}")
        self.return_code = "return"
        self.body(self.statement_nodes(pou))
        self.indent = 0
        self.emit("")

    def gen_function(self, pou: Pou) -> None:
        self.mode = "function"
        params = pou.params()
        outputs = pou.outputs()
        scalar_inouts = [
            p for p in params if p.section == "inout" and p.type.kind not in ("struct", "array", "fb")
        ]
        self.indent = 0
        self.emit(f"def {pou.pyname}({', '.join('v_' + p.name for p in params)}):")
        self.indent = 1
        for p in params:
            if p.section == "in":
                self.emit(f"if v_{p.name} is None:")
                self.emit(f"    v_{p.name} = {self.init_code(p.type, p.init)}")
        self.emit(f"v__ret = {self.default_code(pou.ret)}")
        for n in pou.order:
            v = pou.vars[n]
            if v.section in ("var", "temp", "out"):
                if v.type.kind == "fb":
                    self.diags.append(
                        v.src.diag(
                            pou.node,
                            f"function block instance '{n}' declared inside "
                            f"FUNCTION '{pou.name}' (MatIEC rejects it)",
                        )
                    )
                    continue
                try:
                    self.emit(f"v_{n} = {self.init_code(v.type, v.init)}")
                except _Err as e:
                    self.diags.append(e.diag)
        if outputs or scalar_inouts:
            ret = "return (v__ret, " + "".join(f"v_{v.name}, " for v in outputs + scalar_inouts) + ")"
        else:
            ret = "return v__ret"
        self.return_code = ret
        self.body(self.statement_nodes(pou))
        self.emit(ret)
        self.indent = 0
        self.emit("")

    # ------------------------------------------------------------------ configuration
    def gen_config(self) -> list[tuple[str, str, int]]:
        """Globals class + program instances: [(instance, class, interval_ns)]."""
        instances: list[tuple[str, str, int]] = []
        tasks: dict[str, int] = {}
        self.pou = None
        self.mode = "config"
        self.indent = 0
        if self.config is None:
            programs = [p for p in self.pous.values() if p.kind == "program"]
            self.emit("class Globals:")
            self.emit("    pass")
            if len(programs) == 1:
                instances.append(("inst0", programs[0].pyname, 10_000_000))
            return instances
        node, src = self.config
        self.src = src
        names = list(self.globals)
        self.emit("class Globals:")
        self.emit(f"    __slots__ = ({''.join(repr('v_' + n) + ', ' for n in names)})")
        self.emit("    def __init__(self):")
        self.indent = 2
        for n in names:
            v = self.globals[n]
            try:
                self.emit(f"self.v_{n} = {self.init_code(v.type, v.init)}")
            except _Err as e:
                self.diags.append(e.diag)
        self.emit("pass")
        self.indent = 0

        def walk(n: Node) -> None:
            for c in n.named_children:
                if c.type == "task_declaration":
                    tname = src.node_text(c.named_children[0]).lower()
                    interval = 0
                    for p in c.named_children[1:]:
                        if (
                            p.type == "task_parameter"
                            and src.node_text(p.named_children[0]).upper() == "INTERVAL"
                        ):
                            interval = self.expr(p.named_children[-1]).const or 0
                    tasks[tname] = interval
                elif c.type == "program_assignment":
                    ids = [src.node_text(x) for x in c.named_children if x.type == "identifier"]
                    inst = ids[0].lower()
                    ptype = ids[-1].upper()
                    task = ids[1].lower() if len(ids) == 3 else None
                    if ptype not in self.pous or self.pous[ptype].kind != "program":
                        self.diags.append(src.diag(c, f"unknown PROGRAM '{ids[-1]}'"))
                        continue
                    instances.append((inst, self.pous[ptype].pyname, tasks.get(task, 0) if task else 0))
                elif c.type == "resource_declaration":
                    walk(c)

        walk(node)
        return instances

    def collect_globals(self) -> None:
        if self.config is None:
            return
        node, src = self.config
        for block in node.named_children:
            if block.type == "resource_declaration":
                for b in block.named_children:
                    if b.type == "var_global":
                        self._globals_block(b, src)
            if block.type == "var_global":
                self._globals_block(block, src)

    def _globals_block(self, block: Node, src: ParsedSource) -> None:
        order: list[str] = []
        try:
            self.declare_vars(block, src, self.globals, order)
        except _Err as e:
            self.diags.append(e.diag)

    def check_externals(self) -> None:
        for pou in self.pous.values():
            for v in pou.vars.values():
                if v.section != "ext":
                    continue
                g = self.globals.get(v.name)
                if g is None:
                    self.diags.append(
                        v.src.diag(
                            pou.node,
                            f"VAR_EXTERNAL '{v.name}' of '{pou.name}' has no VAR_GLOBAL in the CONFIGURATION",
                        )
                    )
                elif g.constant and not v.constant:
                    self.diags.append(
                        v.src.diag(
                            pou.node,
                            f"VAR_EXTERNAL '{v.name}' must be declared CONSTANT: "
                            "it maps to a constant global variable",
                        )
                    )

    # ------------------------------------------------------------------ driver
    def compile(self) -> tuple[str, list[tuple[str, str, int]]]:
        self._resolving: set[str] = set()
        self.struct_done: set[str] = set()
        self.struct_pending: list[tuple[str, Type]] = []
        self.pou = None
        self.mode = "config"
        self.pre = []
        self.indent = 0
        self.loop_depth = 0
        self.src = self.sources[0] if self.sources else None
        for src in self.sources:
            self.diags.extend(src.syntax_errors())
        if self.diags:
            return "", []
        self.collect_globals_first()
        self.collect()
        self.check_externals()
        for pou in self.pous.values():
            if pou.failed:
                continue
            try:
                self.gen_pou(pou)
            except _Err as e:
                self.diags.append(e.diag)
        instances = self.gen_config()
        body = self.out
        structs = self.gen_structs()
        code = "\n".join(structs + body) + "\n"
        return code, instances

    def collect_globals_first(self) -> None:
        """Globals are needed for array bounds (VAR_GLOBAL CONSTANT) before the POUs are declared."""
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "configuration_declaration":
                    self.config = (node, src)
        # type references in globals may need TYPEs: collect type nodes first
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "type_declaration":
                    for td in node.named_children:
                        if td.type == "type_definition":
                            self.type_nodes[src.node_text(td.named_children[0]).upper()] = (td, src)
                elif node.type in ("function_block_declaration",):
                    name = src.node_text(node.named_children[0]).upper()
                    self.pous.setdefault(name, Pou("function_block", name, node, src, pyname=f"FB_{name}"))
        try:
            self.collect_globals()
        except _Err as e:
            self.diags.append(e.diag)


RUNTIME_NAMES = (
    "f32 ws8 ws16 ws32 ws64 wu8 wu16 wu32 wu64 idiv imod fdiv ix real_to_sint real_to_uint trunc time_mul "
    "time_div time_to_lreal time_to_int real_to_time int_to_time shl shr rol ror sqrt exp ln log10 sin cos "
    "tan asin acos atan expt limit mux abs_int abs_float INF NAN"
).split()


def _mk(obj, **kw):
    for k, v in kw.items():
        setattr(obj, k, v)
    return obj


def _copy_array(a: list) -> list:
    if a and hasattr(a[0], "_copy"):
        return [e._copy() for e in a]
    if a and isinstance(a[0], list):
        return [_copy_array(e) for e in a]
    return a[:]


def _namespace() -> dict:
    ns: dict = {name: getattr(rt, name) for name in RUNTIME_NAMES}
    ns.update(
        {
            "mk": _mk,
            "copy_array": _copy_array,
            "Ref": rt.Ref,
            "deref": rt.deref,
            "Clock": stdfbs.Clock,
            "min": min,
            "max": max,
        }
    )
    for name, (cls, _) in stdfbs.STANDARD_FBS.items():
        ns[name] = cls
    return ns


def _parse_all(sources: list[tuple[str, str]]) -> list[ParsedSource]:
    return [parse_source(text, filename, blank_pragmas=True) for filename, text in sources]


def typecheck(sources: list[tuple[str, str]]) -> list[Diagnostic]:
    comp = Compiler(_parse_all(sources))
    comp.compile()
    return sorted(set(comp.diags))


def compile_to_python(sources: list[tuple[str, str]]) -> tuple[str, Compiler, list]:
    comp = Compiler(_parse_all(sources))
    code, instances = comp.compile()
    if comp.diags:
        raise StError(sorted(set(comp.diags)))
    return code, comp, instances


def load_application(sources: list[tuple[str, str]]) -> Application:
    code, comp, instances = compile_to_python(sources)
    ns = _namespace()
    clk = stdfbs.Clock()
    ns["CLK"] = clk
    try:
        exec(compile(code, "<thermost-st>", "exec"), ns)  # noqa: S102 - our own generated code
        G = ns["Globals"]()
        ns["G"] = G
        programs = {inst: ns[cls]() for inst, cls, _ in instances}
    except rt.PlcRuntimeError as exc:
        raise StError([Diagnostic(sources[0][0], 1, 1, f"initialisation fault: {exc}")]) from None
    intervals = {inst: iv for inst, _, iv in instances}
    located = _located_vars(comp, programs, G)
    types = {inst: comp.pous[cls.split("_", 1)[1]] for inst, cls, _ in instances}
    return Application(clk, programs, intervals, located, G, types, comp.globals, code)


def _setter(obj, attr: str, t: Type):
    if t.kind == "int":
        wrap = rt.WRAP[(t.bits, t.signed)]
        return lambda v: setattr(obj, attr, wrap(int(v)))
    if t.kind == "real":
        if t is REAL:
            return lambda v: setattr(obj, attr, rt.f32(float(v)))
        return lambda v: setattr(obj, attr, float(v))
    if t.kind == "bool":
        return lambda v: setattr(obj, attr, bool(v))
    return lambda v: setattr(obj, attr, int(v))


def _located_vars(comp: Compiler, programs: dict, G) -> list[LocatedVar]:
    out: list[LocatedVar] = []
    owners: list[tuple[str, object, dict[str, Var]]] = [("", G, comp.globals)]
    for inst, obj in programs.items():
        pou = comp.pous[type(obj).__name__.split("_", 1)[1]]
        owners.append((inst, obj, pou.vars))
    for inst, obj, table in owners:
        for name, v in table.items():
            if not v.location:
                continue
            m = re.fullmatch(r"%([IQM])([XBWDL])?(\d+)(?:\.(\d+))?", v.location)
            if m is None:
                continue
            area, size, index, bit = m.group(1), m.group(2) or "X", int(m.group(3)), m.group(4)
            attr = f"v_{name}"
            out.append(
                LocatedVar(
                    name=v.decl_name or name,
                    instance=inst,
                    location=v.location,
                    area=area,
                    size=size,
                    index=index,
                    bit=int(bit) if bit is not None else None,
                    iec_type=v.type.name,
                    get=(lambda o=obj, a=attr: getattr(o, a)),
                    set=_setter(obj, attr, v.type),
                )
            )
    return out
