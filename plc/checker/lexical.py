"""Text-level scan: comments, C pass-through pragmas and TwinCAT constructs the grammar cannot parse.

MatIEC reads only `(* ... *)` comments without nesting (OpenPLC does not pass iec2c -n); rows
comment_line, comment_cstyle, comment_nested of ../shared/reference/matiec-dialect.md. The scan
also returns a length-preserving copy of the text in which the refused comments and the `{{ C }}`
pragmas (row pragma_c_code, accepted) are blanked, so the tree-sitter parse recovers and every
byte offset, line and column stays that of the user's file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from plc.checker.vocabulary import KEYWORDS


@dataclass
class Finding:
    offset: int  # character offset into the original text
    message: str


@dataclass
class LexicalScan:
    text: str
    blanked: str  # same byte length as text (UTF-8), same lines
    code: list[bool]  # True where the character is code (not comment / string / pragma)
    findings: list[Finding] = field(default_factory=list)
    pragmas: list[int] = field(default_factory=list)  # character offsets of `{...}` pragmas (not `{{ C }}`)


def _blank(chars: list[str], start: int, end: int) -> None:
    for k in range(start, end):
        if chars[k] not in "\r\n":
            chars[k] = " " * len(chars[k].encode("utf-8"))  # keep byte offsets for tree-sitter


def scan(text: str) -> LexicalScan:
    chars = list(text)
    code = [True] * len(text)
    findings: list[Finding] = []
    pragmas: list[int] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("(*", i):
            end, stray = _block_comment_end(text, i)
            if stray is not None:
                inner = text.find("(*", i + 2, end)
                findings.append(
                    Finding(
                        inner if inner >= 0 else i,
                        "nested comment '(* (* *) *)': MatIEC (without -n, as OpenPLC runs it) "
                        "ends the comment at the first '*)' and reads the rest as code",
                    )
                )
                end = stray
                _blank(chars, i, end)
            _mark(code, i, end)
            i = end
        elif text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
            findings.append(Finding(i, "line comment '//' is not accepted by MatIEC; use (* ... *)"))
            _blank(chars, i, end)
            _mark(code, i, end)
            i = end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            findings.append(Finding(i, "C-style comment '/* */' is not accepted by MatIEC; use (* ... *)"))
            _blank(chars, i, end)
            _mark(code, i, end)
            i = end
        elif text.startswith("{{", i):
            end = text.find("}}", i + 2)
            end = n if end < 0 else end + 2
            _blank(chars, i, end)  # C pass-through pragma: accepted by MatIEC, invisible to the grammar
            _mark(code, i, end)
            i = end
        elif c == "{":
            end = text.find("}", i + 1)
            end = n if end < 0 else end + 1
            pragmas.append(i)
            _mark(code, i, end)
            i = end
        elif c in "'\"":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "$" else 1
            end = min(n, j + 1)
            _mark(code, i, end)
            i = end
        else:
            i += 1
    result = LexicalScan(text=text, blanked="".join(chars), code=code, findings=findings, pragmas=pragmas)
    result.findings.extend(_twincat_constructs(result))
    result.findings.sort(key=lambda f: f.offset)
    return result


def _mark(code: list[bool], start: int, end: int) -> None:
    for k in range(start, end):
        code[k] = False


def _block_comment_end(text: str, start: int) -> tuple[int, int | None]:
    """End of the comment opening at `start` as MatIEC reads it (first '*)', no nesting), and, when
    the comment held a nested '(*' whose '*)' closed it early, the end of the stray tail."""
    close = text.find("*)", start + 2)
    if close < 0:
        return len(text), None
    end = close + 2
    if text.find("(*", start + 2, close) < 0:
        return end, None
    next_close = text.find("*)", end)
    next_open = text.find("(*", end)
    if next_close >= 0 and (next_open < 0 or next_close < next_open):
        return end, next_close + 2
    return end, None


# TwinCAT / IEC v3 constructs that tree-sitter either cannot parse or parses into generic nodes.
_TEXT_RULES: list[tuple[re.Pattern[str], str]] = [
    (
        re.compile(r"\bARRAY\s*\[\s*\*", re.I),
        "variable-length ARRAY[*] is not supported by MatIEC; declare fixed bounds",
    ),
    (
        re.compile(r"%[IQM]\*", re.I),
        "incomplete located address (AT %I* / %Q*) is TwinCAT-only; MatIEC needs a full address like %IX0.0",
    ),
    (re.compile(r"\bREFERENCE\s+TO\b", re.I), "REFERENCE TO is TwinCAT-only; MatIEC has REF_TO"),
    (re.compile(r"\bREF=", re.I), "REF= is TwinCAT-only; MatIEC has REF_TO with REF()"),
    (re.compile(r"\bVAR_STAT\b", re.I), "VAR_STAT is TwinCAT-only; MatIEC refuses it"),
    (re.compile(r"\bVAR_INST\b", re.I), "VAR_INST is TwinCAT-only; MatIEC refuses it"),
    (
        re.compile(r"\bVAR(?:_GLOBAL)?(?:\s+RETAIN)?\s+PERSISTENT\b", re.I),
        "VAR PERSISTENT is TwinCAT-only; MatIEC knows VAR RETAIN",
    ),
    (
        re.compile(
            r"(?:^|;)\s*(?:METHOD|PROPERTY)\b\s*(?:PUBLIC|PRIVATE|PROTECTED|INTERNAL|FINAL|ABSTRACT|\s)*"
            r"[A-Za-z_]",
            re.I | re.M,
        ),
        "METHOD/PROPERTY (object-oriented IEC v3 / TwinCAT) is not supported by MatIEC",
    ),
    (
        re.compile(r"(?:^|;)\s*(?:INTERFACE|NAMESPACE)\s+[A-Za-z_]", re.I | re.M),
        "INTERFACE/NAMESPACE (IEC v3 / TwinCAT) is not supported by MatIEC",
    ),
    (
        re.compile(
            r"\bFUNCTION_BLOCK\s+(?:ABSTRACT\s+|FINAL\s+|PUBLIC\s+)*[A-Za-z_]\w*\s+(?:EXTENDS|IMPLEMENTS)\b",
            re.I,
        ),
        "FUNCTION_BLOCK EXTENDS/IMPLEMENTS (inheritance) is not supported by MatIEC",
    ),
    (re.compile(r":\s*UNION\b", re.I), "UNION is TwinCAT-only; MatIEC refuses it"),
    (
        re.compile(r"(?::|\bOF)\s*W?STRING\s*\[", re.I),
        "STRING[n] / STRING(n) length syntax is not accepted by MatIEC; declare plain STRING",
    ),
]
_BIT_ACCESS = re.compile(
    r"(?<![%\w#.])([A-Za-z_]\w*(?:\s*\[[^\]\n]*\]|\s*\.\s*[A-Za-z_]\w*)*)\s*\.\s*(\d+)\b"
)
_SET_RESET = re.compile(
    r"(?:^|;|\bTHEN\b|\bELSE\b|\bDO\b)\s*([A-Za-z_][\w.\[\]]*)\s*([SR])=(?!=)", re.I | re.M
)


def _twincat_constructs(result: LexicalScan) -> list[Finding]:
    text, code = result.text, result.code
    out: list[Finding] = []
    for pattern, message in _TEXT_RULES:
        for m in pattern.finditer(text):
            start = m.start() + (len(m.group(0)) - len(m.group(0).lstrip(";\r\n \t")))
            if code[start]:
                out.append(Finding(start, message))
    for m in _BIT_ACCESS.finditer(text):
        if code[m.start()] and m.group(1).upper() not in KEYWORDS:
            out.append(
                Finding(
                    m.start(),
                    f"bit access '{m.group(1)}.{m.group(2)}' (IEC v3 / TwinCAT) is not "
                    "accepted by MatIEC; use AND with a mask or SHR",
                )
            )
    for m in _SET_RESET.finditer(text):
        if code[m.start(1)] and m.group(1).upper() not in KEYWORDS:
            op = m.group(2).upper()
            out.append(
                Finding(
                    m.start(2),
                    f"'{op}=' set/reset assignment is TwinCAT-only; MatIEC refuses it "
                    "(use IF ... THEN x := TRUE; END_IF;)",
                )
            )
    return out
