"""Lightweight expression typing that reports the type errors MatIEC reports.

Rows of ../shared/reference/matiec-dialect.md: implicit_widening / implicit_int_dint_only
(`dint := int`, `real := int`), int_literal_to_real (`r := 1`), mixed_int_real_expr (`i * r`).
IEC 61131-3 has no implicit conversions and MatIEC types an untyped literal from its context:
an integer literal is ANY_INT (never REAL), a real literal ANY_REAL. The typer is conservative:
whenever a type is unknown (undeclared name, REF_TO, user type from a file not checked, ...)
nothing is reported.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from tree_sitter import Node

from plc.checker.symbols import ArrayT, Pou, Symbols, TypeT, type_of
from plc.checker.vocabulary import (
    ANY_INT,
    ANY_REAL,
    BIT_TYPES,
    ELEMENTARY_TYPES,
    FIXED_RESULT_FUNCTIONS,
    INT_TYPES,
    NUMERIC_TYPES,
    REAL_TYPES,
    SAME_TYPE_FUNCTIONS,
    SELECTION_FUNCTIONS,
    STANDARD_FB_MEMBERS,
    TIME_TYPES,
)

ARITHMETIC_OPS = frozenset({"+", "-", "*", "/", "MOD"})
COMPARISON_OPS = frozenset({"=", "<>", "<", ">", "<=", ">="})
LOGIC_OPS = frozenset({"AND", "OR", "XOR", "&"})
INTLIKE = INT_TYPES | BIT_TYPES
CONVERSION = re.compile(r"^([A-Z_]+?)_TO_([A-Z_]+)$")
LITERAL_TYPES = {
    "integer_literal": ANY_INT,
    "real_literal": ANY_REAL,
    "boolean_literal": "BOOL",
    "string_literal": "STRING",
    "date_literal": "DATE",
    "time_of_day_literal": "TIME_OF_DAY",
    "date_and_time_literal": "DATE_AND_TIME",
}

Report = Callable[[Node, str], None]


def _is_int(t: TypeT) -> bool:
    return t == ANY_INT or t in INTLIKE


def _is_real(t: TypeT) -> bool:
    return t == ANY_REAL or t in REAL_TYPES


def compatibility(target: TypeT, value: TypeT) -> str | None:
    """Why a value of type `value` cannot be stored in `target` without a conversion (or None)."""
    if not isinstance(target, str) or not isinstance(value, str) or target == value:
        return None
    if target in REAL_TYPES and value == ANY_INT:
        return f"integer literal where {target} is expected (write a real literal such as 1.0)"
    if target in INTLIKE and value == ANY_REAL:
        return f"real literal where {target} is expected"
    if target in NUMERIC_TYPES and value in NUMERIC_TYPES:
        return f"{value} value where {target} is expected (convert explicitly with {value}_TO_{target})"
    if (target == "BOOL" and value in NUMERIC_TYPES) or (value == "BOOL" and target in NUMERIC_TYPES):
        return f"{value} value where {target} is expected"
    return None


class ExpressionTyper:
    """Types expressions of one POU; each expression is typed (and reported) once."""

    def __init__(self, symbols: Symbols, pou: Pou, report: Report):
        self.symbols = symbols
        self.pou = pou
        self.ps = pou.source
        self.report = report
        self._memo: dict[int, TypeT] = {}

    # ---- lookups -------------------------------------------------------------------------------
    def variable_type(self, name: str) -> TypeT:
        upper = name.upper()
        var = self.pou.vars.get(upper)
        if var is not None:
            return var.type
        if self.pou.kind == "FUNCTION" and upper == self.pou.name.upper():
            return self.pou.return_type
        owners = self.symbols.enum_members.get(upper)
        if owners and len(owners) == 1:
            return next(iter(owners))
        return None

    def resolve(self, t: TypeT) -> TypeT:
        return self.symbols.resolve(t)

    def member_type(self, owner: TypeT, member: str) -> TypeT:
        owner = self.resolve(owner)
        if not isinstance(owner, str):
            return None
        member = member.upper()
        decl = self.symbols.types.get(owner)
        if decl is not None and decl.kind == "struct":
            return decl.fields.get(member)
        pou = self.symbols.pous.get(owner)
        if pou is not None and pou.kind == "FUNCTION_BLOCK":
            var = pou.vars.get(member)
            return var.type if var is not None else None
        return STANDARD_FB_MEMBERS.get(owner, {}).get(member)

    # ---- typing --------------------------------------------------------------------------------
    def type(self, node: Node | None) -> TypeT:
        if node is None:
            return None
        key = node.id
        if key not in self._memo:
            self._memo[key] = None  # guards against cycles on malformed trees
            self._memo[key] = self._compute(node)
        return self._memo[key]

    def _compute(self, node: Node) -> TypeT:
        kind = node.type
        if kind in LITERAL_TYPES:
            return LITERAL_TYPES[kind]
        if kind == "time_literal":
            return "LTIME" if self.ps.node_text(node).upper().startswith("LT") else "TIME"
        if kind == "typed_literal":
            value = node.child_by_field_name("value")
            for child in node.named_children:
                if child != value and child.type in ("elementary_type", "identifier", "string_type"):
                    return type_of(child, self.ps)
            return None
        if kind == "identifier":
            literal = self.ps.enum_literals.get(node.start_byte)
            if literal is not None:
                return literal[0].upper()
            return self.variable_type(self.ps.node_text(node))
        if kind == "parenthesized_expression":
            inner = [c for c in node.named_children if c.type != "comment"]
            return self.type(inner[0]) if len(inner) == 1 else None
        if kind == "unary_expression":
            return self.type(node.child_by_field_name("operand"))
        if kind == "binary_expression":
            return self._binary(node)
        if kind == "member_access_expression":
            obj = node.child_by_field_name("object")
            member = node.child_by_field_name("member")
            if obj is None or member is None or member.type != "identifier":
                return None
            return self.member_type(self.type(obj), self.ps.node_text(member))
        if kind == "index_expression":
            owner = self.resolve(self.type(node.child_by_field_name("object")))
            return owner.element if isinstance(owner, ArrayT) else None
        if kind == "call_expression":
            return self._call(node)
        return None

    def _binary(self, node: Node) -> TypeT:
        op_node = node.child_by_field_name("operator")
        op = self.ps.node_text(op_node).upper() if op_node is not None else ""
        left = self.resolve(self.type(node.child_by_field_name("left")))
        right = self.resolve(self.type(node.child_by_field_name("right")))
        if op in LOGIC_OPS:
            if left == "BOOL" or right == "BOOL":
                return "BOOL"
            return _unify(left, right)
        if op not in ARITHMETIC_OPS and op not in COMPARISON_OPS:
            return None
        result_if_ok = "BOOL" if op in COMPARISON_OPS else None
        if left in TIME_TYPES or right in TIME_TYPES or left == "LTIME" or right == "LTIME":
            if op in COMPARISON_OPS:
                return "BOOL"
            return left if left in TIME_TYPES else right
        mixed = (_is_int(left) and _is_real(right)) or (_is_real(left) and _is_int(right))
        if mixed and not (left in (ANY_INT, ANY_REAL) and right in (ANY_INT, ANY_REAL)):
            self.report(
                node,
                f"data type mismatch for '{op}': {_describe(left)} and {_describe(right)} operands "
                f"(MatIEC has no implicit conversion; use an explicit *_TO_* conversion"
                f"{' or a real literal such as 2.0' if ANY_INT in (left, right) else ''})",
            )
            return result_if_ok
        if left in NUMERIC_TYPES and right in NUMERIC_TYPES and left != right:
            self.report(
                node,
                f"data type mismatch for '{op}': {left} and {right} operands "
                f"(convert one side explicitly, e.g. {_widening(left, right)})",
            )
            return result_if_ok
        return result_if_ok or _unify(left, right)

    def arguments(self, call: Node) -> list[tuple[str | None, Node, bool]]:
        """(parameter name or None for positional, value node, is_output) of a call."""
        args = call.child_by_field_name("arguments")
        out: list[tuple[str | None, Node, bool]] = []
        if args is None:
            return out
        for child in args.named_children:
            if child.type == "comment":
                continue
            if child.type == "named_argument":
                name = child.child_by_field_name("name")
                value = child.child_by_field_name("value")
                is_output = any(c.type == "=>" for c in child.children)
                if name is not None and value is not None:
                    out.append((self.ps.node_text(name).upper(), value, is_output))
            else:
                out.append((None, child, False))
        return out

    def _call(self, node: Node) -> TypeT:
        fn = node.child_by_field_name("function")
        if fn is None or fn.type != "identifier":
            return None
        name = self.ps.node_text(fn).upper()
        args = self.arguments(node)
        arg_types = [self.resolve(self.type(value)) for _, value, _ in args]
        if name in self.pou.vars:
            return None  # FB instance invocation: no value
        conv = CONVERSION.match(name)
        if conv and conv.group(1) in ELEMENTARY_TYPES and conv.group(2) in ELEMENTARY_TYPES:
            src, dst = conv.group(1), conv.group(2)
            if len(args) == 1 and arg_types[0] is not None:
                why = compatibility(src, arg_types[0])
                if why:
                    self.report(args[0][1], f"incompatible argument of {name}: {why}")
            return dst
        if name in SAME_TYPE_FUNCTIONS:
            return arg_types[0] if arg_types else None
        if name in SELECTION_FUNCTIONS:
            selected = [t for t in arg_types[SELECTION_FUNCTIONS[name]] if t is not None]
            ints = [t for t in selected if _is_int(t)]
            reals = [t for t in selected if _is_real(t)]
            if ints and reals and not all(t in (ANY_INT, ANY_REAL) for t in selected):
                self.report(
                    node,
                    f"data type mismatch in the arguments of {name}: "
                    f"{', '.join(_describe(t) for t in selected)} (all must have one type)",
                )
                return None
            result: TypeT = None
            for i, t in enumerate(arg_types[SELECTION_FUNCTIONS[name]]):
                result = t if i == 0 else _unify(result, t)
            return result
        if name in FIXED_RESULT_FUNCTIONS:
            return FIXED_RESULT_FUNCTIONS[name]
        pou = self.symbols.pous.get(name)
        if pou is not None and pou.kind == "FUNCTION":
            self.check_arguments(node, pou)
            return pou.return_type
        return None

    def check_arguments(self, call: Node, callee: Pou) -> None:
        """Named and positional arguments against the callee's declared parameter types."""
        for position, (pname, value, is_output) in enumerate(self.arguments(call)):
            if pname is None:
                # positional: only when the parameter list is plain VAR_INPUTs, so the order is certain
                if position >= len(callee.inputs) or any(
                    v.section in ("VAR_OUTPUT", "VAR_IN_OUT") for v in callee.vars.values()
                ):
                    continue
                pname = callee.inputs[position]
            param = callee.vars.get(pname)
            if param is None:
                continue
            if is_output:
                why = compatibility(self.resolve(self.type(value)), self.resolve(param.type))
            else:
                why = compatibility(self.resolve(param.type), self.resolve(self.type(value)))
            if why:
                self.report(
                    value, f"incompatible data types for parameter '{param.name}' of {callee.name}: {why}"
                )

    def check_fb_invocation(self, call: Node) -> None:
        fn = call.child_by_field_name("function")
        if fn is None or fn.type != "identifier":
            return
        instance_type = self.resolve(self.variable_type(self.ps.node_text(fn)))
        if not isinstance(instance_type, str):
            return
        callee = self.symbols.pous.get(instance_type)
        if callee is not None and callee.kind == "FUNCTION_BLOCK":
            self.check_arguments(call, callee)
            return
        members = STANDARD_FB_MEMBERS.get(instance_type)
        if members is None:
            return
        for pname, value, is_output in self.arguments(call):
            if pname is None or pname not in members:
                continue
            if is_output:
                why = compatibility(self.resolve(self.type(value)), members[pname])
            else:
                why = compatibility(members[pname], self.resolve(self.type(value)))
            if why:
                self.report(
                    value, f"incompatible data types for parameter '{pname}' of {instance_type}: {why}"
                )

    def check_assignment(self, target: Node, value: Node, where: Node) -> None:
        why = compatibility(self.resolve(self.type(target)), self.resolve(self.type(value)))
        if why:
            self.report(where, f"incompatible data types for ':=': {why}")


def _describe(t: TypeT) -> str:
    return (
        {ANY_INT: "integer literal", ANY_REAL: "real literal"}.get(t, str(t)) if isinstance(t, str) else "?"
    )


# Bytes per elementary type, to suggest the widening conversion in a message.
_WIDTH = {
    "SINT": 1,
    "USINT": 1,
    "BYTE": 1,
    "INT": 2,
    "UINT": 2,
    "WORD": 2,
    "DINT": 4,
    "UDINT": 4,
    "DWORD": 4,
    "REAL": 4,
    "LINT": 8,
    "ULINT": 8,
    "LWORD": 8,
    "LREAL": 8,
}


def _widening(a: str, b: str) -> str:
    narrow, wide = (a, b) if _WIDTH.get(a, 0) <= _WIDTH.get(b, 0) else (b, a)
    return f"{narrow}_TO_{wide}"


def _unify(a: TypeT, b: TypeT) -> TypeT:
    if a == b:
        return a
    if a in (ANY_INT, ANY_REAL) and isinstance(b, str) and b not in (ANY_INT, ANY_REAL):
        return b
    if b in (ANY_INT, ANY_REAL) and isinstance(a, str):
        return a
    return None
