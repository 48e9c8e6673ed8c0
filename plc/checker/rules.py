"""The checker on one file: every family of rules (text, nodes, POUs, TYPEs, naming) in the order they run.

What MatIEC refuses, one method per family of rows of ../shared/reference/matiec-dialect.md (the row names
quoted in the rule modules' comments are that table's).
"""

from __future__ import annotations

from plc.checker.naming_rules import NamingRules
from plc.checker.node_rules import NodeRules
from plc.checker.pou_rules import PouRules
from plc.checker.text_rules import TextRules
from plc.checker.tree import descendants
from plc.st.diagnostics import Diagnostic


class FileChecker(TextRules, NodeRules, PouRules, NamingRules):
    """All rules on one file: lexical findings, text rules, tree rules, POU, TYPE and naming rules."""

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
        for pou in self.index.pous.values():
            if pou.src is self.ps:
                self.pou_rules(pou)
        for node in descendants(root):
            if node.type == "type_definition":
                self.type_definition_rules(node)
        self.naming_rules()
        return self.diagnostics
