"""Rules on single tree nodes anywhere in a file, and on TYPE definitions (rows of matiec-dialect.md)."""

from __future__ import annotations

import math

from tree_sitter import Node

from plc.checker.base import CheckerBase
from plc.checker.tree import POU_KINDS, next_sibling, prev_sibling
from plc.checker.vocabulary import (
    GENERIC_CONVERSIONS,
    TWINCAT_OPERATORS,
    UNSUPPORTED_TYPES,
)
from plc.st.model import Pou

COMPOUND_STATEMENTS = {
    "if_statement": "END_IF",
    "for_statement": "END_FOR",
    "while_statement": "END_WHILE",
    "repeat_statement": "END_REPEAT",
    "case_statement": "END_CASE",
}
# iec2c refuses real literals far outside the binary32 range, even for LREAL ("Numerical value exceeds
# range for LREAL data type"). Evidence (conformance README + corpus): 1.0E39, 1.0E-40, 1.0E308 refused;
# 1.0E-38 (binary32 subnormal) and 3.4028235677973366E38 (FLT_MAX + half an ulp) accepted. The limits
# below sit at the accepted evidence so that no accepted literal is reported.
REAL_LITERAL_MIN = 1.0e-39
REAL_LITERAL_MAX = 3.4028235677973366e38


class NodeRules(CheckerBase):
    """Statements, literals, arrays, calls, member access, TYPEs."""

    # ---- rules on single nodes anywhere --------------------------------------------------------
    def node_rules(self, node: Node) -> None:
        kind = node.type
        if kind in COMPOUND_STATEMENTS:
            nxt = next_sibling(node)
            if nxt is None or nxt.type != "empty_statement":
                self.report_end(node, f"missing ';' after {COMPOUND_STATEMENTS[kind]}")
        elif kind == "empty_statement":
            prev = prev_sibling(node)
            if (
                (prev is None or prev.type not in COMPOUND_STATEMENTS)
                and not self._has_lexical_finding(node)
                and not (node.parent is not None and node.parent.type == "ERROR")
            ):
                self.report(node, "empty statement ';' is refused by MatIEC")
        elif kind == "binary_expression":
            op = node.child_by_field_name("operator")
            if op is not None and op.type == "**":
                self.report(
                    op, "'**' power operator: MatIEC generates C that does not compile; use EXPT(x, y)"
                )
        elif kind == "address_of_expression":
            self.report(node, "ADR() is TwinCAT-only; MatIEC has REF()")
        elif kind == "pointer_type":
            self.report(node, "POINTER TO is TwinCAT-only; MatIEC has REF_TO")
        elif kind == "elementary_type" or kind == "string_type":
            word = self.ps.node_text(node).split("(")[0].split("[")[0].strip().upper()
            if word in UNSUPPORTED_TYPES:
                self.report(node, UNSUPPORTED_TYPES[word])
            elif kind == "string_type" and node.child_by_field_name("length") is not None:
                self.report(
                    node,
                    "STRING(n) / STRING[n] length syntax is not accepted by MatIEC; declare plain STRING",
                )
        elif kind == "array_type":
            self.array_rules(node)
        elif kind == "real_literal":
            self.real_literal_rules(node)
        elif kind == "call_expression":
            self.call_rules(node)
        elif kind == "member_access_expression":
            self.member_access_rules(node)
        elif kind == "assignment_statement":
            left = node.child_by_field_name("left")
            if left is not None and left.type == "dereference_expression":
                self.report(
                    left,
                    "writing through a dereference (r^ := ...) makes MatIEC generate C that does "
                    "not compile; pass the variable as VAR_IN_OUT instead",
                )
        elif kind in (
            "method_declaration",
            "property_declaration",
            "interface_declaration",
            "namespace_declaration",
        ) and not self._has_lexical_finding(node):
            word = kind.split("_")[0].upper()
            self.report(node, f"{word} (object-oriented IEC v3 / TwinCAT) is not supported by MatIEC")

    def _has_lexical_finding(self, node: Node) -> bool:
        line = node.start_point[0] + 1
        return any(d.line == line for d in self.diagnostics)

    def real_literal_rules(self, node: Node) -> None:
        text = self.ps.node_text(node).replace("_", "")
        try:
            value = abs(float(text))
        except ValueError:
            return
        if value != 0.0 and (value < REAL_LITERAL_MIN or value > REAL_LITERAL_MAX or math.isinf(value)):
            self.report(
                node,
                f"real literal {text} is out of range: iec2c refuses literals outside the "
                "binary32 range, even for LREAL",
            )

    def array_rules(self, node: Node) -> None:
        element = node.child_by_field_name("element_type")
        pou = self._enclosing_pou(node)
        if element is not None:
            etype = self.declared_type(element)
            if element.type == "array_type" or (etype is not None and etype.kind == "array"):
                self.report(
                    element,
                    "ARRAY OF ARRAY makes MatIEC generate C that does not compile; "
                    "use a 2-D ARRAY[a..b, c..d]",
                )
            elif etype is not None and etype.kind == "fb":
                self.report(
                    element,
                    f"ARRAY OF function block instances ({self.ps.node_text(element)}) is refused "
                    "by MatIEC; declare the instances one by one",
                )
        for rng in node.children_by_field_name("range"):
            for bound_field in ("lower", "upper"):
                bound = rng.child_by_field_name(bound_field)
                if bound is not None:
                    self.bound_rule(bound, pou)

    def bound_rule(self, bound: Node, pou: Pou | None) -> None:
        if bound.type == "integer_literal":
            return
        if bound.type == "unary_expression":
            operand = bound.child_by_field_name("operand")
            if operand is not None and operand.type == "integer_literal":
                return
        if bound.type == "identifier":
            name = self.ps.node_text(bound).lower()
            var = pou.vars.get(name) if pou is not None else None
            if var is not None and var.section == "ext" and var.constant:
                return
            if var is not None:
                self.report(
                    bound,
                    f"array bound '{self.ps.node_text(bound)}' is a local constant: MatIEC accepts "
                    "only literals or a VAR_EXTERNAL CONSTANT",
                )
            elif pou is None and name in self.index.globals and self.index.globals[name].constant:
                return
            return  # unknown name: leave it to the compiler
        self.report(
            bound,
            f"array bound expression '{self.ps.node_text(bound)}' is refused by MatIEC; "
            "use a literal or a single VAR_EXTERNAL CONSTANT",
        )

    def call_rules(self, node: Node) -> None:
        fn = node.child_by_field_name("function")
        if fn is None or fn.type != "identifier":
            return
        name = self.ps.node_text(fn)
        upper = name.upper()
        if upper in GENERIC_CONVERSIONS:
            self.report(
                fn,
                f"generic conversion {name}() is not accepted by MatIEC; use a typed conversion "
                "such as REAL_TO_INT",
            )
        elif upper in TWINCAT_OPERATORS:
            self.report(fn, f"{name}() is TwinCAT-only; MatIEC refuses it")
        elif self.has_in_out(upper) and (outer := self._enclosing_function_call(node)) is not None:
            self.report(
                fn,
                f"{name}() has VAR_IN_OUT parameters and is called inside the arguments of {outer}(): "
                "iec2c generates C that does not compile (an undeclared temporary); call it in an "
                "assignment of its own and pass the variable",
            )
        elif "_TO_" in upper:
            source = upper.split("_TO_")[0]
            if self.is_enum(source):
                self.report(
                    fn,
                    f"conversion function {name}() of an enumerated type needs iec2c -c, which "
                    "OpenPLC does not pass; map the enum with CASE",
                )

    def member_access_rules(self, node: Node) -> None:
        obj = node.child_by_field_name("object")
        member = node.child_by_field_name("member")
        if obj is None:
            return
        if obj.type == "call_expression":
            self.report(
                node,
                "member access on a function result F().x is refused by MatIEC; "
                "store the result in a variable first",
            )
        elif obj.type == "identifier" and member is not None:
            name = self.ps.node_text(obj)
            pou = self._enclosing_pou(node)
            if self.is_enum(name) and (pou is None or name.lower() not in pou.vars):
                self.report(
                    node,
                    f"enum value written {self.ps.node_text(node)} (TwinCAT qualified access) is "
                    f"refused by MatIEC; write {self.ps.node_text(obj)}#{self.ps.node_text(member)}",
                )

    def _enclosing_pou(self, node: Node) -> Pou | None:
        cur = node.parent
        while cur is not None and cur.type not in POU_KINDS:
            cur = cur.parent
        if cur is None:
            return None
        name = cur.child_by_field_name("name")
        return self.index.pous.get(self.ps.node_text(name).upper()) if name is not None else None

    def has_in_out(self, name: str) -> bool:
        """Whether `name` is a FUNCTION of the program with VAR_IN_OUT parameters."""
        pou = self.index.pous.get(name.upper())
        if pou is None or pou.kind != "function":
            return False
        return any(v.section == "inout" for v in pou.vars.values())

    def _enclosing_function_call(self, node: Node) -> str | None:
        """The function whose arguments hold this call (None: the call stands in a statement or an
        expression of its own, or in the arguments of a function block instance, which iec2c builds)."""
        pou = self._enclosing_pou(node)
        cur = node.parent
        while cur is not None and not cur.type.endswith("_statement"):
            if cur.type == "call_expression":
                fn = cur.child_by_field_name("function")
                if fn is None or fn.type != "identifier":
                    return None
                outer = self.ps.node_text(fn)
                is_instance = pou is not None and outer.lower() in pou.vars
                return None if is_instance else outer
            cur = cur.parent
        return None

    def is_enum(self, name: str) -> bool:
        t = self.named_type(name)
        return t is not None and t.kind == "enum"

    # ---- TYPE rules ----------------------------------------------------------------------------
    def type_definition_rules(self, node: Node) -> None:
        body = node.child_by_field_name("definition")
        if body is None:
            return
        if body.type == "enumerated_type_inline":
            for en in body.named_children:
                if en.type == "enumerator" and en.child_by_field_name("value") is not None:
                    self.report(
                        en,
                        "enumerated value with an explicit value (A := 1) is refused by MatIEC; "
                        "list the names only",
                    )
        if body.type == "identifier":
            for offset, init in self.ps.type_initializers.items():
                if node.start_byte <= offset < node.end_byte and init.lstrip().startswith("("):
                    self.report(
                        body,
                        "named initial values in a derived type declaration (TYPE T2 : T := (...)) "
                        "make MatIEC generate C that does not compile; initialise the variables",
                    )
