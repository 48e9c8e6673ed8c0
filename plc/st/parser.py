"""Parse IEC 61131-3 Structured Text with tree-sitter-iec61131-3-st.

The PyPI grammar lacks a few constructs that MatIEC accepts. A length-preserving pre-pass
rewrites them before parsing, so byte offsets, lines and columns stay those of the user's file:

* `E_Type#Member` (typed enum literal) -> `E_Type_Member`, remembered in `enum_literals`
  by the offset of the identifier;
* underscores inside TIME literals (`T#1s_500ms`) are dropped and padded with blanks;
* pragmas `{...}` / `{{ C }}` are blanked when the caller asks (the soft-PLC runs no C code);
* structure / array initialisers inside a TYPE block (`b : ST_Pt := (x := 1.0);`,
  `T_A : ARRAY[0..3] OF INT := [1, 2(3)];`) are blanked and kept in `type_initializers`
  by the offset of their `:=`; the compiler parses them on their own.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache

import tree_sitter
import tree_sitter_iec61131_3_st

from plc.st.diagnostics import Diagnostic
from plc.st.types import ELEMENTARY

# `X#...` is a typed literal for every elementary type name plus the short and TwinCAT-only prefixes
LITERAL_PREFIXES = set(ELEMENTARY) | {"T", "D", "LT", "LTIME", "WSTRING"}

_ENUM_LITERAL = re.compile(r"\b([A-Za-z_]\w*)#([A-Za-z_]\w*)")
_TIME_LITERAL = re.compile(r"\b(?:T|TIME)#-?[0-9][0-9A-Za-z_.]*", re.IGNORECASE)
_TYPE_BLOCK = re.compile(r"\bTYPE\b(.*?)\bEND_TYPE\b", re.IGNORECASE | re.DOTALL)
_INIT_START = re.compile(r":=\s*([(\[])")


@lru_cache(maxsize=1)
def _parser() -> tree_sitter.Parser:
    return tree_sitter.Parser(tree_sitter.Language(tree_sitter_iec61131_3_st.language()))


# comments `(* *)` (unterminated: to the end), `//` line comments and '...' / "..." strings with `$`
# escapes (unterminated: to the end), found left to right as a scanner would
_NOT_CODE = re.compile(
    r"\(\*[\s\S]*?(?:\*\)|\Z)"  # (* comment *)
    r"|//[^\n]*"  # // line comment
    r"|'(?:\$[\s\S]|[^'$])*(?:'|\$?\Z)"  # 'string'
    r"|\"(?:\$[\s\S]|[^\"$])*(?:\"|\$?\Z)"  # "wide string"
)


def _code_mask(text: str) -> list[bool]:
    """True for characters that are code (not inside comments or string literals)."""
    mask = [True] * len(text)
    for m in _NOT_CODE.finditer(text):
        i, j = m.span()
        mask[i:j] = [False] * (j - i)
    return mask


def _matching(text: str, start: int, mask: list[bool]) -> int:
    """Index just past the bracket group opening at `start` (or -1)."""
    depth = 0
    for k in range(start, len(text)):
        if not mask[k]:
            continue
        if text[k] in "([":
            depth += 1
        elif text[k] in ")]":
            depth -= 1
            if depth == 0:
                return k + 1
    return -1


@dataclass
class ParsedSource:
    filename: str
    text: str
    src: bytes
    tree: tree_sitter.Tree
    enum_literals: dict[int, tuple[str, str]] = field(default_factory=dict)
    type_initializers: dict[int, str] = field(default_factory=dict)

    def node_text(self, node: tree_sitter.Node) -> str:
        return self.src[node.start_byte : node.end_byte].decode("utf-8", "replace")

    def identifiers_in(self, node: tree_sitter.Node) -> set[str]:
        """Upper-case names of every identifier below a node."""
        out: set[str] = set()
        stack = [node]
        while stack:
            cur = stack.pop()
            if cur.type == "identifier":
                out.add(self.node_text(cur).upper())
            stack.extend(cur.children)
        return out

    def position(self, node: tree_sitter.Node) -> tuple[int, int]:
        return node.start_point[0] + 1, node.start_point[1] + 1

    def diag(self, node: tree_sitter.Node, message: str) -> Diagnostic:
        line, col = self.position(node)
        return Diagnostic(self.filename, line, col, message)

    def syntax_errors(self) -> list[Diagnostic]:
        out: list[Diagnostic] = []

        def walk(node: tree_sitter.Node) -> None:
            if node.is_missing:
                out.append(self.diag(node, f"syntax error: missing '{node.type}'"))
                return
            if node.type == "ERROR":
                snippet = self.node_text(node).strip().splitlines()
                near = snippet[0][:40] if snippet else ""
                out.append(self.diag(node, f"syntax error near '{near}'" if near else "syntax error"))
                return
            if node.has_error:
                for child in node.children:
                    walk(child)

        walk(self.tree.root_node)
        return out


def _blank(c: str) -> str:
    """Blank one character with as many spaces as it has UTF-8 bytes (byte columns stay put)."""
    return " " * len(c.encode("utf-8"))


def _rewrite(text: str, blank_pragmas: bool) -> tuple[str, dict[int, tuple[str, str]], dict[int, str]]:
    mask = _code_mask(text)
    chars = list(text)
    enum_literals: dict[int, tuple[str, str]] = {}
    type_inits: dict[int, str] = {}

    for m in _TIME_LITERAL.finditer(text):
        if not mask[m.start()] or "_" not in m.group(0):
            continue
        lit = m.group(0).replace("_", "")
        for k in range(m.start(), m.end()):
            chars[k] = lit[k - m.start()] if k - m.start() < len(lit) else " "

    for m in _ENUM_LITERAL.finditer(text):
        if not mask[m.start()] or m.group(1).upper() in LITERAL_PREFIXES:
            continue
        if m.start() > 0 and (text[m.start() - 1].isalnum() or text[m.start() - 1] == "#"):
            continue
        chars[m.start(1) + len(m.group(1))] = "_"
        enum_literals[m.start()] = (m.group(1), m.group(2))

    # pragmas: `{attribute ...}` and OpenPLC's `{{ C code }}` do not change the ST semantics we run
    k = 0
    for brace in re.finditer(r"\{", text) if blank_pragmas else ():
        if brace.start() < k:
            continue
        k = brace.start()
        if mask[k]:
            depth, j = 0, k
            while j < len(text):
                if text[j] == "{":
                    depth += 1
                elif text[j] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                j += 1
            for q in range(k, min(j + 1, len(text))):
                if chars[q] != "\n":
                    chars[q] = _blank(chars[q])
            k = j + 1

    for block in _TYPE_BLOCK.finditer(text):
        if not mask[block.start()]:
            continue
        for m in _INIT_START.finditer(text, block.start(1), block.end(1)):
            if not mask[m.start()]:
                continue
            end = _matching(text, m.start(1), mask)
            if end < 0:
                continue
            type_inits[m.start()] = text[m.start(1) : end]
            for k in range(m.start(), end):
                if chars[k] != "\n":
                    chars[k] = _blank(chars[k])
    return "".join(chars), enum_literals, type_inits


def _byte_offsets(text: str, offsets: dict) -> dict:
    """Character offsets -> byte offsets (identical for ASCII sources)."""
    if text.isascii():
        return offsets
    return {len(text[:k].encode("utf-8")): v for k, v in offsets.items()}


def parse_source(text: str, filename: str = "<string>", blank_pragmas: bool = False) -> ParsedSource:
    """Parse; with blank_pragmas the runtime ignores `{...}` pragmas (the checker wants to see them)."""
    rewritten, enum_literals, type_inits = _rewrite(text, blank_pragmas)
    src = rewritten.encode("utf-8")
    tree = _parser().parse(src)
    return ParsedSource(
        filename=filename,
        text=text,
        src=src,
        tree=tree,
        enum_literals=_byte_offsets(text, enum_literals),
        type_initializers=_byte_offsets(text, type_inits),
    )
