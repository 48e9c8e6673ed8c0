"""MatIEC's type rules on typed expressions, and the C classes they take.

IEC side: which operand types an operator, a comparison, a standard function or an assignment
accepts (the diagnostics are MatIEC's wording). C side: the usual arithmetic conversions MatIEC's
generated C applies (`common_c`), and the code that converts an operand to a C class (`to_c`) or
stores a value into a variable of a given type (`convert_store`: wrap-around, float rounding,
copies of structured values).
"""

from __future__ import annotations

import re

from tree_sitter import Node

from plc.st.literals import int_const_code, real_const_code
from plc.st.model import Ex, c_of, type_label
from plc.st.types import ANY_INT, ANY_REAL, REAL, TIME, Type


def common_c(a: str, b: str) -> str:
    """C's usual arithmetic conversions on the classes of two operands."""
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


def literal_c(lit: Ex, other: Ex) -> Ex:
    """An untyped integer literal takes the C class of its typed partner."""
    if lit.t.kind == "anyint" and other.t.kind == "int":
        return Ex(lit.code, other.t, c_of(other.t), lit.const)
    return lit


def arith_type(ctx, a: Ex, b: Ex, op: str, node: Node) -> Type:
    ta, tb = a.t, b.t
    if ta.kind == "time" or tb.kind == "time":
        if ta.kind == "time" and tb.kind == "time" and op in "+-":
            return TIME
        if ta.kind == "time" and tb.is_num() and op in "*/":
            return TIME
        raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression")
    if not (ta.is_num() and tb.is_num()):
        raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression")
    if ta.kind in ("anyint", "anyreal") and tb.kind in ("anyint", "anyreal"):
        if ta.kind != tb.kind:  # iec2c: `1 + 0.5` has no type (an integer and a real literal)
            raise ctx.err(
                ctx.src,
                node,
                f"Data type mismatch for '{op}' expression (integer literal with a real literal: "
                "write both as real literals)",
            )
        return ta
    if ta.kind in ("anyint", "anyreal"):
        ta, tb = tb, ta
        a, b = b, a
    # ta is typed now
    if tb.kind == "anyint":
        if ta.kind == "real":
            raise ctx.err(
                ctx.src,
                node,
                f"Data type mismatch for '{op}' expression "
                f"(integer literal with {ta.name}: write a real literal)",
            )
        return ta
    if tb.kind == "anyreal":
        if ta.kind == "int":
            raise ctx.err(
                ctx.src,
                node,
                f"Data type mismatch for '{op}' expression ({ta.name} with a real literal)",
            )
        return ta
    if ta is not tb and ta.name != tb.name:
        raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression ({ta.name} {op} {tb.name})")
    return ta


def bit_type(ctx, a: Ex, b: Ex, op: str, node: Node) -> Type:
    if a.t.kind in ("int", "anyint") and b.t.kind in ("int", "anyint"):
        if a.t.kind == "int" and b.t.kind == "int" and a.t.name != b.t.name:
            raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression ({a.t.name}, {b.t.name})")
        return a.t if a.t.kind == "int" else b.t
    raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression ({a.t.name}, {b.t.name})")


def compare_types(ctx, a: Ex, b: Ex, op: str, node: Node) -> None:
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
            raise ctx.err(
                ctx.src, node, f"Data type mismatch for '{op}' expression ({typed.name}, real literal)"
            )
        if typed.kind == "real" and lit.kind == "anyint":
            raise ctx.err(
                ctx.src,
                node,
                f"Data type mismatch for '{op}' expression ({typed.name}, integer literal)",
            )
        return
    if ta.name != tb.name and not (ta.kind == tb.kind == "time"):
        raise ctx.err(ctx.src, node, f"Data type mismatch for '{op}' expression ({ta.name}, {tb.name})")


def _subject(what: str) -> str:
    """What a failed store is: an operation (`':='`, an initial value) or a parameter of a call."""
    return what if what.startswith("parameter ") else f"{what} operation"


def convert_store(ctx, e: Ex, dst: Type, node: Node, what: str = "':='") -> str:
    """Code that stores expression e into a variable of type dst, with MatIEC's type rules."""
    src_t = e.t
    if dst.kind == "int":
        if src_t.kind == "anyint":
            if e.const is not None:
                return int_const_code(e.const, dst)
            return f"w{'s' if dst.signed else 'u'}{dst.bits}({e.code})"
        if src_t.kind == "int" and src_t.name == dst.name:
            wrap = f"w{'s' if dst.signed else 'u'}{dst.bits}"
            if not needs_wrap(e) or e.code.startswith(wrap + "("):
                return e.code
            return f"{wrap}({e.code})"
        raise ctx.err(
            ctx.src,
            node,
            f"Incompatible data types for {_subject(what)} "
            f"({type_label(src_t)} to {dst.name}: use an explicit conversion)",
        )
    if dst.kind == "real":
        if src_t.kind == "anyreal" or (src_t.kind == "real" and src_t.name == dst.name):
            if dst is REAL and e.c != "f":
                if e.const is not None:
                    return real_const_code(e.const)
                return f"f32({e.code})"
            return e.code
        raise ctx.err(
            ctx.src,
            node,
            f"Incompatible data types for {_subject(what)} "
            f"({type_label(src_t)} to {dst.name}"
            + (
                ": write a real literal such as 1.0)"
                if src_t.kind == "anyint"
                else ": use an explicit conversion)"
            ),
        )
    if dst.kind == "bool":
        if src_t.kind == "bool":
            return e.code
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to BOOL)"
        )
    if dst.kind == "time":
        if src_t.kind == "time":
            return e.code
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to TIME)"
        )
    if dst.kind == "enum":
        if src_t is dst or (src_t.kind == "enum" and src_t.name == dst.name):
            return e.code
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to {dst.name})"
        )
    if dst.kind in ("struct", "fb"):
        if src_t.kind == dst.kind and src_t.name == dst.name:
            return f"{e.code}._copy()"
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to {dst.name})"
        )
    if dst.kind == "array":
        if src_t.kind == "array" and same_array(src_t, dst):
            return f"copy_array({e.code})"
        raise ctx.err(ctx.src, node, f"Incompatible data types for {_subject(what)} (array shapes differ)")
    if dst.kind == "ref":
        if src_t.kind == "ref" and (src_t.elem is None or src_t.elem.name == dst.elem.name):
            return e.code
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to {dst.name})"
        )
    if dst.kind == "string":
        if src_t.kind == "string":
            return e.code
        raise ctx.err(
            ctx.src, node, f"Incompatible data types for {_subject(what)} ({type_label(src_t)} to STRING)"
        )
    raise ctx.err(ctx.src, node, f"cannot assign to a value of type {dst.name}")


def needs_wrap(e: Ex) -> bool:
    return not re.fullmatch(r"[A-Za-z_][\w.]*(\[[^\]]*\])?", e.code)


def same_array(a: Type, b: Type) -> bool:
    return (
        a.dims == b.dims
        and a.elem is not None
        and b.elem is not None
        and (a.elem is b.elem or a.elem.name == b.elem.name)
    )


def common_arg_type(ctx, args: list[Ex], node: Node, name: str) -> Type:
    typed = [a.t for a in args if a.t.kind not in ("anyint", "anyreal")]
    if not typed:
        kinds = {a.t.kind for a in args}
        if kinds == {"anyint", "anyreal"}:  # iec2c: MAX(1, 10.0) resolves to no overload
            raise ctx.err(
                ctx.src,
                node,
                f"{name}: integer and real literals mixed (write them all as real literals, e.g. 1.0)",
            )
        return ANY_REAL if "anyreal" in kinds else ANY_INT
    t = typed[0]
    for o in typed[1:]:
        if o.name != t.name:
            raise ctx.err(ctx.src, node, f"{name}: arguments of different types ({t.name}, {o.name})")
    return t


def as_type(ctx, a: Ex, t: Type, node: Node, name: str) -> str:
    if t.kind in ("anyint", "anyreal"):
        return a.code
    return convert_store(ctx, a, t, node, what=f"{name} argument")
