"""Naming rules: reserved words, standard names, underscores, names clashing with POUs or types."""

from __future__ import annotations

import re

from tree_sitter import Node

from plc.checker.base import CheckerBase
from plc.checker.tree import POU_KINDS, descendants
from plc.checker.vocabulary import (
    is_reserved,
    is_standard_function,
    naming_problem,
)

_DECLARED_NAMES = re.compile(
    r"^[ \t]*([A-Za-z_]\w*(?:[ \t]*,[ \t]*[A-Za-z_]\w*)*)[ \t]*(?:AT[ \t]+%\S+[ \t]*)?:(?!=)", re.I | re.M
)
_VAR_REGION = re.compile(
    r"\b(?:VAR|VAR_INPUT|VAR_OUTPUT|VAR_IN_OUT|VAR_TEMP|VAR_EXTERNAL|VAR_GLOBAL|VAR_STAT|VAR_INST|STRUCT)\b"
    r"(.*?)\bEND_(?:VAR|STRUCT)\b",
    re.I | re.S,
)


class NamingRules(CheckerBase):
    """Every declared name of a file against MatIEC's naming rows."""

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
                owner = self.index.pous.get(name.upper())
                if owner is not None:
                    self.report(
                        name_node,
                        f"variable '{name}' has the same name as the POU '{owner.written}' "
                        "(MatIEC refuses it)",
                    )
                elif name.upper() in self.index.type_nodes:
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
