"""Rules on POUs: declarations, bodies, initial values, the use of globals (rows of matiec-dialect.md)."""

from __future__ import annotations

from tree_sitter import Node

from plc.checker.base import CheckerBase
from plc.checker.tree import VAR_SECTIONS, block_qualifiers, declared_names, descendants, var_blocks
from plc.st.codegen import initial_value_fits
from plc.st.model import Pou
from plc.st.types import Type

# iec2c crashes on one declaration of three or more function block instances (probed on OpenPLC v3's
# iec2c: `t1, t2 : TON;` compiles, `t1, t2, t3 : TON;` ends with a segmentation fault)
MAX_FB_NAMES_PER_DECLARATION = 2
POU_KIND_WORDS = {"function": "FUNCTION", "function_block": "FUNCTION_BLOCK", "program": "PROGRAM"}


class PouRules(CheckerBase):
    """Declarations and bodies of FUNCTIONs, FUNCTION_BLOCKs and PROGRAMs."""

    # ---- POU rules -----------------------------------------------------------------------------
    def pou_rules(self, pou: Pou) -> None:
        node, ps = pou.node, self.ps
        name_node = node.child_by_field_name("name")
        blocks = var_blocks(node)
        kind, written = POU_KIND_WORDS[pou.kind], pou.written
        if pou.kind == "function":
            return_type = node.child_by_field_name("return_type")
            if return_type is not None and ps.node_text(return_type).upper() == "VOID":
                self.report(
                    return_type,
                    f"FUNCTION '{written}' : VOID needs iec2c -b, which OpenPLC does not pass; "
                    "declare a return type",
                )
            if not pou.params() and not node.has_error:
                self.report(
                    name_node,
                    f"FUNCTION '{written}' has no inputs (VAR_INPUT / VAR_IN_OUT): MatIEC "
                    f"refuses the call {written}() without parameters",
                )
            for var in pou.vars.values():
                if var.type.kind == "fb" and var.node is not None:
                    self.report(
                        var.node,
                        f"function block instance '{var.decl_name}' inside a FUNCTION is refused by "
                        "MatIEC; use a FUNCTION_BLOCK",
                    )
        for block in blocks:
            quals = block_qualifiers(block, ps.node_text)
            section = VAR_SECTIONS[block.type]
            if section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT") and "CONSTANT" in quals:
                self.report(block, f"{section} CONSTANT is TwinCAT-only; MatIEC refuses it")
            variables = declared_names(block)
            self.multi_instance_rule(block)
            located = [name for name, is_located in variables if is_located]
            if located and pou.kind != "program":
                for name in located:
                    self.report(
                        name,
                        f"located variable '{ps.node_text(name)}' inside a {kind}: MatIEC accepts "
                        "located variables only in a PROGRAM or CONFIGURATION",
                    )
            elif located and len(located) != len(variables):
                for name in located:
                    self.report(
                        name,
                        f"located variable '{ps.node_text(name)}' shares its VAR block with unlocated "
                        "variables; MatIEC needs located variables in a block of their own",
                    )
            if section == "VAR_EXTERNAL" and "CONSTANT" not in quals:
                for name, _ in variables:
                    glob = self.index.globals.get(ps.node_text(name).lower())
                    if glob is not None and glob.constant:
                        self.report(
                            name,
                            f"VAR_EXTERNAL '{ps.node_text(name)}' must be declared CONSTANT: it maps to a "
                            "VAR_GLOBAL CONSTANT",
                        )
        body = node.children_by_field_name("body")
        if not [b for b in body if b.type != "comment"]:
            self.report(
                name_node, f"{kind} '{written}' has an empty body; MatIEC needs at least one statement"
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
            vtype = self.declared_type(decl.child_by_field_name("type"))
            if len(names) >= MAX_FB_NAMES_PER_DECLARATION + 1 and vtype is not None and vtype.kind == "fb":
                self.report(
                    names[0],
                    f"{len(names)} function block instances in one declaration crash MatIEC's iec2c "
                    "(segmentation fault); declare one instance per line",
                )

    def body_rules(self, pou: Pou, body: list[Node]) -> None:
        for block in var_blocks(pou.node):
            for decl in block.named_children:
                if decl.type != "variable_declaration":
                    continue
                inits = decl.children_by_field_name("initial_value")
                vtype = self.declared_type(decl.child_by_field_name("type")) if inits else None
                if len(inits) == 1 and vtype is not None and inits[0].type == "structure_initializer":
                    self.member_lookup_rule(vtype, inits[0])
        for stmt in body:
            if stmt.has_error:
                continue  # a statement the grammar could not parse is reported as a syntax error only
            for node in descendants(stmt):
                kind = node.type
                if kind == "assignment_statement":
                    left = node.child_by_field_name("left")
                    if left is not None and left.type == "identifier" and not pou.node.has_error:
                        self.undeclared_target_rule(pou, left)  # declarations all parsed
                elif kind == "identifier":
                    self.global_use_rule(pou, node)

    def member_lookup_rule(self, struct: Type, init: Node) -> None:
        """iec2c checks the value of `member := value` in a structure initialiser against the first
        member, in declaration order, whose upper-case name is not below MEMBER's: a search that
        assumes the members are sorted by name. When that is another member of another type, the
        value is judged against the wrong type (a real literal for a member found as INT is refused,
        an enumerated value ends in an internal compiler error). Members declared in alphabetical
        order, or set in code, avoid it. Values are typed by the compiler's rules."""
        if struct.kind != "struct":
            return
        for fld in init.named_children:
            name, value = fld.child_by_field_name("name"), fld.child_by_field_name("value")
            if fld.type != "structure_initializer_field" or name is None or value is None:
                continue
            member = self.ps.node_text(name)
            mtype = struct.fields.get(member.lower())
            if mtype is None:
                continue
            if value.type == "structure_initializer":
                self.member_lookup_rule(mtype, value)
            found = next((f for f in struct.fields if f.upper() >= member.upper()), member.lower())
            ftype = struct.fields[found] if found in struct.fields else None
            if found == member.lower() or ftype is None or ftype is mtype or ftype.kind == "unknown":
                continue
            fits = initial_value_fits(self.index, self.ps, value, mtype)
            if fits and not initial_value_fits(self.index, self.ps, value, ftype):
                self.report(
                    value,
                    f"iec2c checks the initial value of '{member}' against member '{found}' ({ftype.name}), "
                    "the first member at or after it in alphabetical order, and refuses it; declare the "
                    "members in alphabetical order or set this one in code",
                )

    def undeclared_target_rule(self, pou: Pou, target: Node) -> None:
        name = self.ps.node_text(target).lower()
        if name in pou.vars or name.upper() == pou.name or name in self.index.globals:
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
        name = self.ps.node_text(node)
        if name.lower() in pou.vars or name.upper() == pou.name or name.upper() in self.index.pous:
            return
        if name.lower() in self.index.globals and name.upper() not in self.index.enum_members:
            self.report(
                node,
                f"'{self.ps.node_text(node)}' is a CONFIGURATION global used without a "
                "VAR_EXTERNAL declaration in this POU (MatIEC refuses it)",
            )
