"""Literals and constant folding, in one place.

Integer, real, boolean, TIME / DATE / TOD / DT, string and typed (`INT#5`) literals become `Ex`
values with their compile-time value; `fold` evaluates an operator on two untyped constants the
way MatIEC does (C arithmetic on the literal's class). Generated code prints floats with
`py_float`, so NaN and infinities survive the round trip.
"""

from __future__ import annotations

import calendar
import re

from tree_sitter import Node

from plc.st import rt
from plc.st.model import Ex, c_of, int_range, py_float
from plc.st.types import ANY_INT, ANY_REAL, BOOL, ELEMENTARY, REAL, STRING, TIME, Type


def literal(ctx, node: Node) -> Ex | None:
    """The `Ex` of a literal node, or None when the node is not a literal."""
    src = ctx.src
    k = node.type
    if k == "integer_literal":
        return lit_int(int_literal(src.node_text(node)))
    if k == "real_literal":
        text = src.node_text(node).replace("_", "")
        value = float(text)
        return Ex(py_float(value), ANY_REAL, "d", value)
    if k == "boolean_literal":
        value = src.node_text(node).upper() == "TRUE"
        return Ex(repr(value), BOOL, "bool", value)
    if k == "time_literal":
        ns = time_literal(ctx, src.node_text(node), node)
        return Ex(repr(ns), TIME, "time", ns)
    if k == "typed_literal":
        return typed_literal(ctx, node)
    if k in ("date_literal", "time_of_day_literal", "date_and_time_literal"):
        ns, tname = date_literal(ctx, src.node_text(node), node)
        return Ex(repr(ns), ELEMENTARY[tname], "time", ns)
    if k in ("string_literal", "character_string"):
        text = src.node_text(node)
        return Ex(repr(text[1:-1].replace("$$", "$").replace("$N", "\n").replace("$'", "'")), STRING, "str")
    return None


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


def lit_int(value: int, t: Type = ANY_INT) -> Ex:
    c = "i32" if -(1 << 31) <= value < (1 << 31) else "i64"
    if t.kind == "int":
        c = c_of(t)
    return Ex(repr(value), t, c, value)


def time_literal(ctx, text: str, node: Node) -> int:
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
        raise ctx.err(ctx.src, node, f"invalid TIME literal '{text}'")
    ns = rt.time_literal_ns(sign, parts["ms"], parts["s"], parts["m"], parts["h"], parts["d"])
    return ns + sign * extra_ns


def date_literal(ctx, text: str, node: Node) -> tuple[int, str]:
    """D#, TOD#, DT# literals as nanoseconds since 1970-01-01 (MatIEC's timespec epoch)."""
    prefix, body = text.split("#", 1)
    prefix = prefix.upper()
    body = body.replace("_", "")
    try:
        if prefix in ("D", "DATE"):
            y, m, d = (int(x) for x in body.split("-"))
            return calendar.timegm((y, m, d, 0, 0, 0)) * rt.NS, "DATE"
        if prefix in ("TOD", "TIME_OF_DAY"):
            return tod_ns(body), "TIME_OF_DAY"
        y, m, d, tod = body.split("-", 3)
        return calendar.timegm((int(y), int(m), int(d), 0, 0, 0)) * rt.NS + tod_ns(tod), "DATE_AND_TIME"
    except ValueError:
        raise ctx.err(ctx.src, node, f"invalid date/time literal '{text}'") from None


def tod_ns(body: str) -> int:
    h, m, sec = body.split(":")
    return rt.time_literal_ns(1, 0.0, float(sec), float(m), float(h), 0.0)


def typed_literal(ctx, node: Node) -> Ex:
    src = ctx.src
    tname = src.node_text(node.named_children[0]).upper()
    val = node.named_children[-1]
    t = ELEMENTARY.get(tname)
    if t is None:
        raise ctx.err(src, node, f"unknown literal type '{tname}'")
    text = src.node_text(val)
    if t.kind == "int":
        if val.type == "boolean_literal":
            v = int(text.upper() == "TRUE")
        else:
            v = int_literal(text)
        lo, hi = int_range(t)
        if not lo <= v <= hi:
            raise ctx.err(src, node, f"literal {text} out of range for {tname}")
        return Ex(repr(v), t, c_of(t), v)
    if t.kind == "real":
        v = float(int_literal(text)) if val.type == "integer_literal" else float(text.replace("_", ""))
        if t is REAL:
            v = rt.f32(v)
        return Ex(py_float(v), t, c_of(t), v)
    if t.kind == "bool":
        v = text.upper() in ("TRUE", "1")
        return Ex(repr(v), BOOL, "bool", v)
    if t.kind == "time":
        ns = time_literal(ctx, "T#" + text, node)
        return Ex(repr(ns), TIME, "time", ns)
    raise ctx.err(src, node, f"unsupported typed literal '{src.node_text(node)}'")


def fold(ctx, a: Ex, b: Ex, op: str, t: Type, node: Node) -> Ex:
    x, y = a.const, b.const
    if t.kind == "anyint":
        if op == "/":
            if y == 0:
                raise ctx.err(ctx.src, node, "division by zero in a constant expression")
            v = rt.idiv(x, y)
        elif op == "MOD":
            v = rt.imod(x, y)
        else:
            v = {"+": x + y, "-": x - y, "*": x * y}[op]
        return lit_int(v)
    x, y = float(x), float(y)
    v = rt.fdiv(x, y) if op == "/" else {"+": x + y, "-": x - y, "*": x * y}[op]
    return Ex(py_float(v), ANY_REAL, "d", v)


def negate(a: Ex) -> Ex:
    """Unary minus on an untyped constant."""
    if a.t.kind == "anyint":
        return lit_int(-a.const)
    return Ex(py_float(-a.const), ANY_REAL, "d", -a.const)


def int_const_code(value: int, dst: Type) -> str:
    """An integer constant stored into a variable of integer type dst (wraps like C)."""
    return repr(rt.WRAP[(dst.bits, dst.signed)](value))


def real_const_code(value: object) -> str:
    """A real constant stored into a REAL (rounded to binary32 at compile time)."""
    return py_float(rt.f32(float(value)))
