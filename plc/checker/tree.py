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
