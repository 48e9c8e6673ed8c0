"""Program-wide declarations the checker needs: POUs, their variables, derived types and globals.

Collected from every file of one `thermost check` run, so a library split into one POU per
file is typed as a whole (MatIEC is run with -p, forward references allowed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tree_sitter import Node

from plc.st.parser import ParsedSource

TYPE_SYNONYMS = {"TOD": "TIME_OF_DAY", "DT": "DATE_AND_TIME"}

VAR_SECTIONS = {
    "var_block": "VAR",
    "var_input": "VAR_INPUT",
    "var_output": "VAR_OUTPUT",
    "var_in_out": "VAR_IN_OUT",
    "var_temp": "VAR_TEMP",
    "var_external": "VAR_EXTERNAL",
    "var_global": "VAR_GLOBAL",
}
POU_KINDS = {
    "function_declaration": "FUNCTION",
    "function_block_declaration": "FUNCTION_BLOCK",
    "program_declaration": "PROGRAM",
}


@dataclass(frozen=True)
class ArrayT:
    element: TypeT
    dims: int


TypeT = str | ArrayT | None  # str: upper-case elementary or derived type name; None: unknown


@dataclass
class VarInfo:
    name: str
    type: TypeT
    section: str
    constant: bool
    located: bool
    node: Node


@dataclass
class Pou:
    kind: str
    name: str
    node: Node
    source: ParsedSource
    return_type: TypeT = None
    vars: dict[str, VarInfo] = field(default_factory=dict)
    inputs: list[str] = field(default_factory=list)  # upper-case, declaration order (VAR_INPUT, VAR_IN_OUT)


@dataclass
class TypeDecl:
    name: str
    kind: str  # enum | struct | alias | subrange | array | other
    target: TypeT = None
    fields: dict[str, TypeT] = field(default_factory=dict)
    members: list[str] = field(default_factory=list)


@dataclass
class Symbols:
    pous: dict[str, Pou] = field(default_factory=dict)
    types: dict[str, TypeDecl] = field(default_factory=dict)
    enum_members: dict[str, set[str]] = field(default_factory=dict)
    globals: dict[str, VarInfo] = field(default_factory=dict)

    def resolve(self, t: TypeT) -> TypeT:
        """Follow aliases and subranges to an elementary, array, struct or enum type."""
        seen: set[str] = set()
        while isinstance(t, str) and t in self.types and t not in seen:
            seen.add(t)
            decl = self.types[t]
            if decl.kind in ("alias", "subrange", "array"):
                t = decl.target
            else:
                return t
        return t

    def is_enum(self, t: TypeT) -> bool:
        t = self.resolve(t)
        return isinstance(t, str) and t in self.types and self.types[t].kind == "enum"

    def is_fb_type(self, t: TypeT) -> bool:
        from plc.checker.vocabulary import STANDARD_FBS

        return isinstance(t, str) and (
            t in STANDARD_FBS or (t in self.pous and self.pous[t].kind == "FUNCTION_BLOCK")
        )


def type_of(node: Node | None, ps: ParsedSource) -> TypeT:
    """The declared type written at `node` (a type node of the grammar)."""
    if node is None:
        return None
    kind = node.type
    if kind in ("elementary_type", "string_type"):
        word = ps.node_text(node).split("(")[0].split("[")[0].strip().upper()
        return TYPE_SYNONYMS.get(word, word)
    if kind == "identifier":
        word = ps.node_text(node).upper()
        return TYPE_SYNONYMS.get(word, word)
    if kind == "array_type":
        return ArrayT(
            type_of(node.child_by_field_name("element_type"), ps), len(node.children_by_field_name("range"))
        )
    if kind == "subrange_type":
        for child in node.named_children:
            if child.type == "elementary_type":
                return type_of(child, ps)
    return None


def var_blocks(pou_node: Node) -> list[Node]:
    return [c for c in pou_node.named_children if c.type in VAR_SECTIONS]


def block_qualifiers(block: Node, ps: ParsedSource) -> set[str]:
    quals: set[str] = set()
    for c in block.named_children:
        if c.type == "var_qualifier_list":
            quals.update(ps.node_text(q).upper() for q in c.named_children)
    return quals


def block_variables(block: Node, ps: ParsedSource) -> list[VarInfo]:
    section = VAR_SECTIONS[block.type]
    constant = "CONSTANT" in block_qualifiers(block, ps)
    out = []
    for decl in block.named_children:
        if decl.type != "variable_declaration":
            continue
        vtype = type_of(decl.child_by_field_name("type"), ps)
        located = decl.child_by_field_name("address") is not None
        for name in (n for n in decl.children_by_field_name("names") if n.type == "identifier"):
            out.append(VarInfo(ps.node_text(name), vtype, section, constant, located, name))
    return out


def _collect_type(defn: Node, ps: ParsedSource, symbols: Symbols) -> None:
    name_node = defn.child_by_field_name("name")
    body = defn.child_by_field_name("definition")
    if name_node is None or defn.has_error:
        return  # a definition the grammar could not parse is only reported, never trusted
    name = ps.node_text(name_node).upper()
    decl = TypeDecl(name=name, kind="other")
    if body is None:
        pass
    elif body.type == "enumerated_type_inline":
        decl.kind = "enum"
        for en in body.named_children:
            member = en.child_by_field_name("name")
            if member is not None:
                decl.members.append(ps.node_text(member).upper())
                symbols.enum_members.setdefault(decl.members[-1], set()).add(name)
    elif body.type == "structure_type_inline":
        decl.kind = "struct"
        for fld in body.named_children:
            if fld.type == "structure_field" and fld.child_by_field_name("name") is not None:
                decl.fields[ps.node_text(fld.child_by_field_name("name")).upper()] = type_of(
                    fld.child_by_field_name("type"), ps
                )
    elif body.type == "subrange_type":
        decl.kind, decl.target = "subrange", type_of(body, ps)
    elif body.type == "array_type":
        decl.kind, decl.target = "array", type_of(body, ps)
    elif body.type in ("elementary_type", "identifier", "string_type"):
        decl.kind, decl.target = "alias", type_of(body, ps)
    symbols.types[name] = decl


def collect(sources: list[ParsedSource]) -> Symbols:
    symbols = Symbols()
    for ps in sources:
        for node in _walk_top(ps.tree.root_node):
            if node.type == "type_definition":
                _collect_type(node, ps, symbols)
            elif node.type in POU_KINDS:
                name_node = node.child_by_field_name("name")
                if name_node is None:
                    continue
                pou = Pou(
                    POU_KINDS[node.type],
                    ps.node_text(name_node),
                    node,
                    ps,
                    type_of(node.child_by_field_name("return_type"), ps),
                )
                for block in var_blocks(node):
                    for var in block_variables(block, ps):
                        pou.vars[var.name.upper()] = var
                        if var.section in ("VAR_INPUT", "VAR_IN_OUT"):
                            pou.inputs.append(var.name.upper())
                symbols.pous[pou.name.upper()] = pou
            elif node.type == "configuration_declaration":
                for block in node.named_children:
                    if block.type == "var_global":
                        for var in block_variables(block, ps):
                            symbols.globals[var.name.upper()] = var
    return symbols


def _walk_top(root: Node):
    """Top-level declarations, looking inside TYPE blocks and (refused) NAMESPACEs."""
    for node in root.named_children:
        if node.type == "type_declaration":
            if node.has_error:
                continue  # a TYPE block that did not parse is reported, its names are not trusted
            yield from (c for c in node.named_children if c.type == "type_definition")
        elif node.type == "namespace_declaration":
            yield from _walk_top(node)
        else:
            yield node
