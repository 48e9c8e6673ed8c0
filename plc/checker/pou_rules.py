"""Rules on POUs: declarations, bodies, initial values, the use of globals (rows of matiec-dialect.md)."""

from __future__ import annotations

from tree_sitter import Node

from plc.checker.base import CheckerBase
from plc.checker.symbols import (
    VAR_SECTIONS,
    Pou,
    TypeT,
    block_qualifiers,
    block_variables,
    type_of,
    var_blocks,
)
from plc.checker.tree import descendants
from plc.checker.typing_rules import ExpressionTyper, compatibility

# iec2c crashes on one declaration of three or more function block instances (probed on OpenPLC v3's
# iec2c: `t1, t2 : TON;` compiles, `t1, t2, t3 : TON;` ends with a segmentation fault)
MAX_FB_NAMES_PER_DECLARATION = 2


class PouRules(CheckerBase):
    """Declarations and bodies of FUNCTIONs, FUNCTION_BLOCKs and PROGRAMs."""

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
