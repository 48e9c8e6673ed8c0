"""Tree helpers shared by the checker's rules."""

from __future__ import annotations

from collections.abc import Iterator

from tree_sitter import Node


def descendants(node: Node) -> Iterator[Node]:
    cursor = [node]
    while cursor:
        current = cursor.pop()
        yield current
        cursor.extend(reversed(current.children))


def next_sibling(node: Node) -> Node | None:
    sib = node.next_sibling
    while sib is not None and sib.type == "comment":
        sib = sib.next_sibling
    return sib


def prev_sibling(node: Node) -> Node | None:
    sib = node.prev_sibling
    while sib is not None and sib.type == "comment":
        sib = sib.prev_sibling
    return sib


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


def var_blocks(pou_node: Node) -> list[Node]:
    return [c for c in pou_node.named_children if c.type in VAR_SECTIONS]


def block_qualifiers(block: Node, text_of) -> set[str]:
    quals: set[str] = set()
    for c in block.named_children:
        if c.type == "var_qualifier_list":
            quals.update(text_of(q).upper() for q in c.named_children)
    return quals


def declared_names(block: Node) -> list[tuple[Node, bool]]:
    """(name node, located) of every variable a VAR block declares."""
    out = []
    for decl in block.named_children:
        if decl.type != "variable_declaration":
            continue
        located = decl.child_by_field_name("address") is not None
        out.extend((n, located) for n in decl.children_by_field_name("names") if n.type == "identifier")
    return out
