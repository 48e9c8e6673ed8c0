"""The semantic model the stages share: declared variables, POUs and typed expressions.

`plc.st.index` fills `Var` and `Pou` from the declarations; the generators in `plc.st.codegen`
produce an `Ex` per expression: its IEC type (MatIEC's type rules and diagnostics), the C class
MatIEC's generated code gives it (float vs double, integer promotion) and, for literals and
folded constants, its compile-time value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from tree_sitter import Node

from plc.st.diagnostics import Diagnostic
from plc.st.parser import ParsedSource
from plc.st.types import Type

SECTION_OF = {
    "var_input": "in",
    "var_output": "out",
    "var_in_out": "inout",
    "var_block": "var",
    "var_temp": "temp",
    "var_external": "ext",
    "var_global": "global",
}
PY_PREFIX = {"function": "FN", "function_block": "FB", "program": "PR"}


class CompileError(Exception):
    """One diagnostic; the stage that catches it records it and goes on with the next declaration."""

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
    node: Node | None = None  # the name where it is declared


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

    @property
    def written(self) -> str:
        """Its name as the declaration writes it."""
        name = self.node.child_by_field_name("name")
        return self.src.node_text(name) if name is not None else self.name

    def params(self) -> list[Var]:
        return [self.vars[n] for n in self.order if self.vars[n].section in ("in", "inout")]

    def outputs(self) -> list[Var]:
        return [self.vars[n] for n in self.order if self.vars[n].section == "out"]

    def types(self) -> list[Type]:
        """The declared types of its variables and result."""
        return [v.type for v in self.vars.values()] + ([self.ret] if self.ret is not None else [])


@dataclass
class Ex:
    code: str
    t: Type  # IEC type (ANY_INT / ANY_REAL for untyped literals and their combinations)
    c: str  # C class: i32 u32 i64 u64 f d bool time str enum struct array fb
    const: object = None  # compile-time value for literals


NULL_REF = Type("NULL", "ref")


def c_of(t: Type) -> str:
    if t.kind in ("struct", "array", "fb", "string", "time", "ref"):
        return t.kind
    if t.kind == "bool":
        return "bool"
    return t.ctype


def type_label(t: Type) -> str:
    """Type name for messages (untyped literals read as such)."""
    return {"anyint": "integer literal", "anyreal": "real literal"}.get(t.kind, t.name)


def int_range(t: Type) -> tuple[int, int]:
    if t.signed:
        return -(1 << (t.bits - 1)), (1 << (t.bits - 1)) - 1
    return 0, (1 << t.bits) - 1


def py_float(x: float) -> str:
    if x != x:
        return "NAN"
    if math.isinf(x):
        return "INF" if x > 0 else "(-INF)"
    return repr(float(x))
