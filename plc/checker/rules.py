"""Tree rules: what MatIEC refuses, one method per family of rows of the dialect table.

The row names quoted in the messages' comments are those of ../shared/reference/matiec-dialect.md.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator

from tree_sitter import Node

from plc.checker.lexical import LexicalScan
from plc.checker.symbols import (
    POU_KINDS,
    VAR_SECTIONS,
    ArrayT,
    Pou,
    Symbols,
    TypeT,
    block_qualifiers,
    block_variables,
    type_of,
    var_blocks,
)
from plc.checker.typing_rules import ExpressionTyper, compatibility
from plc.checker.vocabulary import (
    ANY_INT,
    ANY_REAL,
    GENERIC_CONVERSIONS,
    TWINCAT_OPERATORS,
    UNSUPPORTED_TYPES,
    is_reserved,
    is_standard_function,
    naming_problem,
)
from plc.st.diagnostics import Diagnostic
from plc.st.parser import ParsedSource

COMPOUND_STATEMENTS = {
    "if_statement": "END_IF",
    "for_statement": "END_FOR",
    "while_statement": "END_WHILE",
    "repeat_statement": "END_REPEAT",
    "case_statement": "END_CASE",
}
# iec2c crashes on one declaration of three or more function block instances (probed on OpenPLC v3's
# iec2c: `t1, t2 : TON;` compiles, `t1, t2, t3 : TON;` ends with a segmentation fault)
MAX_FB_NAMES_PER_DECLARATION = 2
# iec2c refuses real literals far outside the binary32 range, even for LREAL ("Numerical value exceeds
# range for LREAL data type"). Evidence (conformance README + corpus): 1.0E39, 1.0E-40, 1.0E308 refused;
# 1.0E-38 (binary32 subnormal) and 3.4028235677973366E38 (FLT_MAX + half an ulp) accepted. The limits
# below sit at the accepted evidence so that no accepted literal is reported.
REAL_LITERAL_MIN = 1.0e-39
REAL_LITERAL_MAX = 3.4028235677973366e38

_FUNCTION_WITHOUT_TYPE = re.compile(r"^[ \t]*FUNCTION[ \t]+([A-Za-z_]\w*)[ \t]*(?=\r?\n|$)", re.I | re.M)
_ENUM_BASE_TYPE = re.compile(
    r"\)\s*(SINT|INT|DINT|LINT|USINT|UINT|UDINT|ULINT|BYTE|WORD|DWORD|LWORD)\s*(?:;|:=)", re.I
)
_ARRAY_OF_STRUCT_INIT = re.compile(r"\bOF\s+[A-Za-z_]\w*\s*:=\s*\[[^\]]*?\(\s*[A-Za-z_]\w*\s*:=", re.I)
_DECLARED_NAMES = re.compile(
    r"^[ \t]*([A-Za-z_]\w*(?:[ \t]*,[ \t]*[A-Za-z_]\w*)*)[ \t]*(?:AT[ \t]+%\S+[ \t]*)?:(?!=)", re.I | re.M
)
_VAR_REGION = re.compile(
    r"\b(?:VAR|VAR_INPUT|VAR_OUTPUT|VAR_IN_OUT|VAR_TEMP|VAR_EXTERNAL|VAR_GLOBAL|VAR_STAT|VAR_INST|STRUCT)\b"
    r"(.*?)\bEND_(?:VAR|STRUCT)\b",
    re.I | re.S,
)


def descendants(node: Node) -> Iterator[Node]:
    cursor = [node]
    while cursor:
        current = cursor.pop()
        yield current
        cursor.extend(reversed(current.children))


def _next_sibling(node: Node) -> Node | None:
    sib = node.next_sibling
    while sib is not None and sib.type == "comment":
        sib = sib.next_sibling
    return sib


def _prev_sibling(node: Node) -> Node | None:
    sib = node.prev_sibling
    while sib is not None and sib.type == "comment":
        sib = sib.prev_sibling
    return sib


class FileChecker:
    def __init__(self, ps: ParsedSource, lexical: LexicalScan, symbols: Symbols):
        self.ps = ps
        self.lexical = lexical
        self.symbols = symbols
        self.diagnostics: list[Diagnostic] = []

    # ---- reporting -----------------------------------------------------------------------------
    def report(self, node: Node, message: str) -> None:
        self.diagnostics.append(self.ps.diag(node, message))

    def report_end(self, node: Node, message: str) -> None:
        row, col = node.end_point
        self.diagnostics.append(Diagnostic(self.ps.filename, row + 1, col + 1, message))

    def report_offset(self, offset: int, message: str) -> None:
        text = self.lexical.text
        line = text.count("\n", 0, offset) + 1
        col = len(text[text.rfind("\n", 0, offset) + 1 : offset].encode("utf-8")) + 1  # bytes, as tree-sitter
        self.diagnostics.append(Diagnostic(self.ps.filename, line, col, message))

    # ---- driver --------------------------------------------------------------------------------
    def run(self) -> list[Diagnostic]:
        for finding in self.lexical.findings:
            self.report_offset(finding.offset, finding.message)
        self.text_rules()
        self.missing_type_semicolon_rule()
        self.pragma_rules()
        # a construct recognised above explains the parse error on its line: report it only once
        specific = {d.line for d in self.diagnostics}
        self.diagnostics.extend(d for d in self.ps.syntax_errors() if d.line not in specific)
        root = self.ps.tree.root_node
        for node in root.named_children:
            if node.type == "global_var_declaration_block":
                self.report(
                    node,
                    "VAR_GLOBAL outside a CONFIGURATION (TwinCAT GVL style) is refused by MatIEC; "
                    "declare globals in CONFIGURATION ... VAR_GLOBAL",
                )
        for node in descendants(root):
            self.node_rules(node)
        for pou in self.symbols.pous.values():
            if pou.source is self.ps:
                self.pou_rules(pou)
        for node in descendants(root):
            if node.type == "type_definition":
                self.type_definition_rules(node)
        self.naming_rules()
        return self.diagnostics

    # ---- text rules for constructs the grammar cannot represent ---------------------------------
    def text_rules(self) -> None:
        text, code = self.lexical.text, self.lexical.code
        for m in _FUNCTION_WITHOUT_TYPE.finditer(text):
            if code[m.start(1)]:
                self.report_offset(
                    m.start(1),
                    f"FUNCTION '{m.group(1)}' has no return type (TwinCAT style); "
                    "MatIEC needs FUNCTION name : type",
                )
        for m in _ENUM_BASE_TYPE.finditer(text):
            if code[m.start(1)]:
                self.report_offset(
                    m.start(1),
                    f"enumerated type with a base type ({m.group(1)}) is TwinCAT-only; MatIEC refuses it",
                )
        for m in _ARRAY_OF_STRUCT_INIT.finditer(text):
            if code[m.start()]:
                self.report_offset(
                    m.start(),
                    "ARRAY OF STRUCT initializer [(x := ...), ...] is refused by MatIEC; "
                    "assign the elements in the body",
                )

    def pragma_rules(self) -> None:
        """Rows pragma_attr_pou (top level: accepted), pragma_attr_var and pragma_attr_body (refused).

        The parser blanks pragmas, so their place is found from the enclosing tree node."""
        text, root = self.lexical.text, self.ps.tree.root_node
        for offset in self.lexical.pragmas:
            byte = len(text[:offset].encode("utf-8"))
            cur: Node | None = root.descendant_for_byte_range(byte, byte)
            while cur is not None and cur.type not in VAR_SECTIONS and cur.type not in POU_KINDS:
                cur = cur.parent
            if cur is None:
                continue
            if cur.type in VAR_SECTIONS:
                self.report_offset(
                    offset, "pragma inside a VAR block (attribute on a variable) is refused by MatIEC"
                )
            else:
                self.report_offset(
                    offset,
                    "pragma inside a POU body is copied into the generated C, which then "
                    "fails to compile; use (* *) comments",
                )

    def missing_type_semicolon_rule(self) -> None:
        """Rows end_type_semicolon / enum_no_semicolon: ';' after END_STRUCT or ')' inside TYPE."""
        for node in descendants(self.ps.tree.root_node):
            if node.is_missing and node.type == ";" and node.parent is not None:
                if node.parent.type == "type_definition":
                    self.report(
                        node,
                        "missing ';' at the end of the data type declaration (after END_STRUCT "
                        "or the enumeration's ')')",
                    )

    # ---- rules on single nodes anywhere --------------------------------------------------------
    def node_rules(self, node: Node) -> None:
        kind = node.type
        if kind in COMPOUND_STATEMENTS:
            nxt = _next_sibling(node)
            if nxt is None or nxt.type != "empty_statement":
                self.report_end(node, f"missing ';' after {COMPOUND_STATEMENTS[kind]}")
        elif kind == "empty_statement":
            prev = _prev_sibling(node)
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
            etype = type_of(element, self.ps)
            if element.type == "array_type" or isinstance(self.symbols.resolve(etype), ArrayT):
                self.report(
                    element,
                    "ARRAY OF ARRAY makes MatIEC generate C that does not compile; "
                    "use a 2-D ARRAY[a..b, c..d]",
                )
            elif self.symbols.is_fb_type(etype):
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
            name = self.ps.node_text(bound).upper()
            var = pou.vars.get(name) if pou is not None else None
            if var is not None and var.section == "VAR_EXTERNAL" and var.constant:
                return
            if var is not None:
                self.report(
                    bound,
                    f"array bound '{self.ps.node_text(bound)}' is a local constant: MatIEC accepts "
                    "only literals or a VAR_EXTERNAL CONSTANT",
                )
            elif pou is None and name in self.symbols.globals and self.symbols.globals[name].constant:
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
        elif "_TO_" in upper:
            source = upper.split("_TO_")[0]
            if self.symbols.is_enum(source):
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
            name = self.ps.node_text(obj).upper()
            pou = self._enclosing_pou(node)
            if self.symbols.is_enum(name) and (pou is None or name not in pou.vars):
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
        return self.symbols.pous.get(self.ps.node_text(name).upper()) if name is not None else None

    # ---- POU rules -----------------------------------------------------------------------------
    def pou_rules(self, pou: Pou) -> None:
        node, ps = pou.node, self.ps
        name_node = node.child_by_field_name("name")
        blocks = var_blocks(node)
        if pou.kind == "FUNCTION":
            if pou.return_type == "VOID":
                self.report(
                    node.child_by_field_name("return_type"),
                    f"FUNCTION '{pou.name}' : VOID needs iec2c -b, which OpenPLC does not pass; "
                    "declare a return type",
                )
            if not pou.inputs and not node.has_error:
                self.report(
                    name_node,
                    f"FUNCTION '{pou.name}' has no inputs (VAR_INPUT / VAR_IN_OUT): MatIEC "
                    f"refuses the call {pou.name}() without parameters",
                )
            for var in pou.vars.values():
                if self.symbols.is_fb_type(self.symbols.resolve(var.type)):
                    self.report(
                        var.node,
                        f"function block instance '{var.name}' inside a FUNCTION is refused by "
                        "MatIEC; use a FUNCTION_BLOCK",
                    )
        for block in blocks:
            quals = block_qualifiers(block, ps)
            section = VAR_SECTIONS[block.type]
            if section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and "CONSTANT" in quals:
                self.report(block, f"{section} CONSTANT is TwinCAT-only; MatIEC refuses it")
            variables = block_variables(block, ps)
            self.multi_instance_rule(block)
            located = [v for v in variables if v.located]
            if located and pou.kind != "PROGRAM":
                for var in located:
                    self.report(
                        var.node,
                        f"located variable '{var.name}' inside a {pou.kind}: MatIEC accepts "
                        "located variables only in a PROGRAM or CONFIGURATION",
                    )
            elif located and len(located) != len(variables):
                for var in located:
                    self.report(
                        var.node,
                        f"located variable '{var.name}' shares its VAR block with unlocated "
                        "variables; MatIEC needs located variables in a block of their own",
                    )
            if section == "VAR_EXTERNAL" and "CONSTANT" not in quals:
                for var in variables:
                    glob = self.symbols.globals.get(var.name.upper())
                    if glob is not None and glob.constant:
                        self.report(
                            var.node,
                            f"VAR_EXTERNAL '{var.name}' must be declared CONSTANT: it maps to a "
                            "VAR_GLOBAL CONSTANT",
                        )
        body = node.children_by_field_name("body")
        if not [b for b in body if b.type != "comment"]:
            self.report(
                name_node, f"{pou.kind} '{pou.name}' has an empty body; MatIEC needs at least one statement"
            )
        self.body_rules(pou, body)

    def multi_instance_rule(self, block: Node) -> None:
        """iec2c (OpenPLC v3) ends with a segmentation fault on one declaration of three or more
        function block instances (`a, b, c : TON;`) once the POU is instantiated in a CONFIGURATION
        (as every OpenPLC program is); two names, or one per line, compile."""
        for decl in block.named_children:
            if decl.type != "variable_declaration":
                continue
            names = [n for n in decl.children_by_field_name("names") if n.type == "identifier"]
            vtype = self.symbols.resolve(type_of(decl.child_by_field_name("type"), self.ps))
            if len(names) >= MAX_FB_NAMES_PER_DECLARATION + 1 and self.symbols.is_fb_type(vtype):
                self.report(
                    names[0],
                    f"{len(names)} function block instances in one declaration crash MatIEC's iec2c "
                    "(segmentation fault); declare one instance per line",
                )

    def body_rules(self, pou: Pou, body: list[Node]) -> None:
        typer = ExpressionTyper(self.symbols, pou, self.report)
        for block in var_blocks(pou.node):
            for decl in block.named_children:
                if decl.type != "variable_declaration":
                    continue
                inits = decl.children_by_field_name("initial_value")
                vtype = self.symbols.resolve(type_of(decl.child_by_field_name("type"), self.ps))
                if len(inits) == 1 and isinstance(vtype, str):
                    self.initial_value_rule(typer, vtype, inits[0])
        for stmt in body:
            if stmt.has_error:
                continue  # a statement the grammar could not parse is reported as a syntax error only
            for node in descendants(stmt):
                kind = node.type
                if kind == "assignment_statement":
                    left, right = node.child_by_field_name("left"), node.child_by_field_name("right")
                    if left is not None and right is not None:
                        typer.check_assignment(left, right, node)  # MatIEC points at the statement
                    if left is not None and left.type == "identifier" and not pou.node.has_error:
                        self.undeclared_target_rule(pou, left)  # declarations all parsed
                elif kind == "invocation_statement":
                    for call in node.named_children:
                        if call.type == "call_expression":
                            if (
                                self.ps.node_text(call.child_by_field_name("function") or call).upper()
                                in pou.vars
                            ):
                                typer.check_fb_invocation(call)
                            else:
                                typer.type(call)
                elif kind in ("binary_expression", "call_expression"):
                    typer.type(node)
                elif kind == "identifier":
                    self.global_use_rule(pou, node)

    def initial_value_rule(self, typer: ExpressionTyper, vtype: TypeT, init: Node) -> None:
        """Initial value against the declared type; named initialisers field by field."""
        if init.type == "structure_initializer":
            for fld in init.named_children:
                name, value = fld.child_by_field_name("name"), fld.child_by_field_name("value")
                if fld.type != "structure_initializer_field" or name is None or value is None:
                    continue
                ftype = self.symbols.resolve(typer.member_type(vtype, self.ps.node_text(name)))
                if isinstance(ftype, str):
                    self.initial_value_rule(typer, ftype, value)
                    self.member_lookup_rule(typer, vtype, self.ps.node_text(name), ftype, value)
            return
        why = compatibility(vtype, self.symbols.resolve(typer.type(init)))
        if why:
            self.report(init, f"incompatible initial value: {why}")

    def member_lookup_rule(self, typer: ExpressionTyper, struct: str, member: str, mtype: str,
                           value: Node) -> None:
        """iec2c checks the value of `member := value` in a structure initialiser against the first
        member, in declaration order, whose upper-case name is not below MEMBER's: a search that
        assumes the members are sorted by name. When that is another member of another type, the
        value is judged against the wrong type (a real literal for a member found as INT is refused,
        an enumerated value ends in an internal compiler error). Members declared in alphabetical
        order, or set in code, avoid it."""
        decl = self.symbols.types.get(struct)
        if decl is None or decl.kind != "struct":
            return
        key = member.upper()
        found = next((name for name in decl.fields if name >= key), key)
        ftype = self.symbols.resolve(decl.fields.get(found))
        if found == key or not isinstance(ftype, str) or ftype == mtype:
            return
        vtype = self.symbols.resolve(typer.type(value))
        why = compatibility(ftype, vtype)
        enum_value = isinstance(vtype, str) and vtype in self.symbols.types and vtype != ftype
        if why or enum_value:
            self.report(
                value,
                f"iec2c checks the initial value of '{member}' against member '{found}' ({ftype}), the "
                "first member at or after it in alphabetical order, and refuses it; declare the "
                "members in alphabetical order or set this one in code",
            )

    def undeclared_target_rule(self, pou: Pou, target: Node) -> None:
        name = self.ps.node_text(target).upper()
        if name in pou.vars or name == pou.name.upper() or name in self.symbols.globals:
            return  # globals used without VAR_EXTERNAL have their own message
        self.report(target, f"variable '{self.ps.node_text(target)}' is not declared in this POU")

    def global_use_rule(self, pou: Pou, node: Node) -> None:
        parent = node.parent
        if (
            parent is not None
            and parent.type == "member_access_expression"
            and parent.child_by_field_name("member") == node
        ):
            return
        if (
            parent is not None
            and parent.type == "named_argument"
            and parent.child_by_field_name("name") == node
        ):
            return
        name = self.ps.node_text(node).upper()
        if name in pou.vars or name == pou.name.upper() or name in self.symbols.pous:
            return
        if name in self.symbols.globals and name not in self.symbols.enum_members:
            self.report(
                node,
                f"'{self.ps.node_text(node)}' is a CONFIGURATION global used without a "
                "VAR_EXTERNAL declaration in this POU (MatIEC refuses it)",
            )

    # ---- TYPE rules ----------------------------------------------------------------------------
    def struct_default_rules(self, body: Node) -> None:
        """Default values of STRUCT members against the member type (same rule as initial values)."""
        for fld in body.named_children:
            default = fld.child_by_field_name("default") if fld.type == "structure_field" else None
            if default is None:
                continue
            ftype = self.symbols.resolve(type_of(fld.child_by_field_name("type"), self.ps))
            value = default
            if value.type == "unary_expression":
                value = value.child_by_field_name("operand") or value
            literal = {"integer_literal": ANY_INT, "real_literal": ANY_REAL}.get(value.type)
            why = compatibility(ftype, literal) if isinstance(ftype, str) and literal else None
            if why:
                self.report(default, f"incompatible initial value: {why}")

    def type_definition_rules(self, node: Node) -> None:
        body = node.child_by_field_name("definition")
        if body is None:
            return
        if body.type == "structure_type_inline":
            self.struct_default_rules(body)
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

    # ---- naming rules --------------------------------------------------------------------------
    def naming_rules(self) -> None:
        declared: list[tuple[Node, str]] = []  # (node, kind)
        for node in descendants(self.ps.tree.root_node):
            if node.type in POU_KINDS or node.type == "type_definition":
                name = node.child_by_field_name("name")
                if name is not None:
                    declared.append((name, "name"))
            elif node.type in ("enumerator", "structure_field"):
                name = node.child_by_field_name("name")
                if name is not None:
                    declared.append((name, node.type))
            elif node.type == "variable_declaration":
                names = node.children_by_field_name("names")
                declared.extend((n, "variable") for n in names if n.type == "identifier")
        seen: set[int] = set()
        for name_node, kind in declared:
            name = self.ps.node_text(name_node)
            seen.add(name_node.start_byte)
            self.name_rule(name, kind, lambda msg, n=name_node: self.report(n, msg))
            if kind == "variable":
                owner = self.symbols.pous.get(name.upper())
                if owner is not None:
                    self.report(
                        name_node,
                        f"variable '{name}' has the same name as the POU '{owner.name}' (MatIEC refuses it)",
                    )
                elif name.upper() in self.symbols.types:
                    self.report(
                        name_node, f"variable '{name}' has the same name as a data type (MatIEC refuses it)"
                    )
        # declarations the grammar could not parse (a keyword as a name breaks the tree)
        text, code = self.lexical.text, self.lexical.code
        for region in _VAR_REGION.finditer(text):
            if not code[region.start()]:
                continue
            for m in _DECLARED_NAMES.finditer(text, region.start(1), region.end(1)):
                for word in re.finditer(r"[A-Za-z_]\w*", m.group(1)):
                    offset = m.start(1) + word.start()
                    if code[offset] and len(text[:offset].encode("utf-8")) not in seen:
                        self.name_rule(
                            word.group(0), "variable", lambda msg, o=offset: self.report_offset(o, msg)
                        )

    @staticmethod
    def name_rule(name: str, kind: str, report) -> None:
        problem = naming_problem(name) or is_reserved(name)
        if problem is None and kind in ("variable", "enumerator") and is_standard_function(name):
            # iec2c refuses these as variables and enum values; STRUCT members and POU names pass
            problem = f"'{name}' is a standard function of MatIEC's library and cannot name a {kind}"
        if problem:
            report(problem)
