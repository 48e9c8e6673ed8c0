"""MatIEC-strict checker: refuses what OpenPLC v3's iec2c refuses (see docs/checker.md).

`check_sources([(filename, text), ...])` returns sorted diagnostics (`file:line:col: message`);
`main_check(args)` is the `thermost check FILE...` sub-command (a directory stands for its .st
files): exit 0 when clean, 1 when any error, 2 (one line) when a file cannot be read or is empty.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from plc.checker.lexical import scan
from plc.checker.rules import FileChecker
from plc.cli import UserError, read_text_file
from plc.st.compiler import analyse
from plc.st.diagnostics import Diagnostic
from plc.st.parser import parse_source


def check_sources(sources: list[tuple[str, str]]) -> list[Diagnostic]:
    """Check several files as one program (declarations of every file are visible to all)."""
    scans = [scan(text) for _, text in sources]
    parsed = [parse_source(sc.blanked, filename) for sc, (filename, _) in zip(scans, sources, strict=True)]
    for ps, (_, text) in zip(parsed, sources, strict=True):
        ps.text = text
    index, typing = analyse(parsed)  # the compiler's index and typing rules, once for the program
    found: set[Diagnostic] = set(typing)
    for ps, sc in zip(parsed, scans, strict=True):
        found.update(FileChecker(ps, sc, index).run())
    return sorted(found, key=lambda d: (d.filename, d.line, d.col, d.message))


def _expand(paths: list[str]) -> list[str]:
    """Files as given; a directory stands for the .st files below it (sorted)."""
    out: list[str] = []
    for path in paths:
        if os.path.isdir(path):
            out.extend(sorted(str(p) for p in Path(path).rglob("*.st")))
        else:
            out.append(path)
    return out


def main_check(args: argparse.Namespace) -> int:
    sources: list[tuple[str, str]] = []
    names = _expand(args.files)
    if not names:
        raise UserError(f"no .st files in {', '.join(args.files)}")
    for name in names:
        try:
            sources.append((name, read_text_file(name, "ST file", code=True)))
        except UserError as exc:  # the checker's own format: file:line:col: message
            reason = str(exc).removeprefix(f"{name}: ")
            what = "" if reason.startswith("empty") else "cannot read file: "
            sys.stderr.write(f"{name}:1:1: {what}{reason}\n")
            return 2
    diagnostics = check_sources(sources)
    for d in diagnostics:
        sys.stdout.write(f"{d}\n")
    return 1 if diagnostics else 0
