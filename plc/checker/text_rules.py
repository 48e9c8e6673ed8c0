"""Rules on the source text, for constructs the grammar cannot represent (rows of matiec-dialect.md)."""

from __future__ import annotations

import re

from tree_sitter import Node

from plc.checker.base import CheckerBase
from plc.checker.tree import POU_KINDS, VAR_SECTIONS, descendants

_FUNCTION_WITHOUT_TYPE = re.compile(r"^[ \t]*FUNCTION[ \t]+([A-Za-z_]\w*)[ \t]*(?=\r?\n|$)", re.I | re.M)
_ENUM_BASE_TYPE = re.compile(
    r"\)\s*(SINT|INT|DINT|LINT|USINT|UINT|UDINT|ULINT|BYTE|WORD|DWORD|LWORD)\s*(?:;|:=)", re.I
)
_ARRAY_OF_STRUCT_INIT = re.compile(r"\bOF\s+[A-Za-z_]\w*\s*:=\s*\[[^\]]*?\(\s*[A-Za-z_]\w*\s*:=", re.I)


class TextRules(CheckerBase):
    """Text, pragma and TYPE-terminator rules."""

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
