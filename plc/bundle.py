"""`thermost bundle -o FILE.st`: the single file a user uploads to OpenPLC v3.

Sources: every `st_lib/**/*.st` except the shims of other targets (only `st_lib/shim/openplc/`
is kept), plus `plc/app/*.st`. Each top-level declaration (TYPE block, FUNCTION,
FUNCTION_BLOCK, PROGRAM, CONFIGURATION) is cut out with the comments in front of it, and
the declarations are written in dependency order: TYPEs, FUNCTIONs, FUNCTION_BLOCKs,
PROGRAMs, CONFIGURATION last. A declaration depends on another when it names one of the
other's identifiers (case-insensitive, comments and strings ignored). Ties are broken by
kind, then name, so the output is deterministic (no timestamps).
"""

from __future__ import annotations

import argparse
import heapq
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

from plc.cli import UserError, writable_file

ROOT = Path(__file__).resolve().parents[1]
LIBRARY_DIR = "st_lib"
SHIM_DIR = "shim"
OPENPLC_SHIM = "openplc"
APP_DIR = Path("plc") / "app"

KIND_RANK = {"TYPE": 0, "FUNCTION": 1, "FUNCTION_BLOCK": 2, "PROGRAM": 3, "CONFIGURATION": 4}
END_KEYWORD = {kind: f"END_{kind}" for kind in KIND_RANK}
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_START = re.compile(r"\b(TYPE|FUNCTION_BLOCK|FUNCTION|PROGRAM|CONFIGURATION)\b", re.IGNORECASE)
_COMMENT_OR_STRING = re.compile(r"\(\*.*?\*\)|'[^']*'|\"[^\"]*\"", re.DOTALL)


@dataclass
class Declaration:
    """One top-level declaration of a source file, with the comments in front of it."""

    kind: str
    names: list[str]  # declared names (a TYPE block may declare several), original spelling
    path: str
    text: str
    uses: set[str] = field(default_factory=set)  # upper-case identifiers referenced

    @property
    def sort_key(self) -> tuple[int, str, str]:
        return (KIND_RANK[self.kind], self.names[0].upper() if self.names else "", self.path)


def mask_comments_and_strings(text: str) -> str:
    """Same length, comments and string literals blanked (newlines kept)."""
    return _COMMENT_OR_STRING.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def _type_names(body: str) -> list[str]:
    """Names declared in a masked TYPE ... END_TYPE body: `name :` outside STRUCT/()/[]."""
    names: list[str] = []
    depth = 0
    tokens = re.finditer(r"[A-Za-z_][A-Za-z0-9_]*|[()\[\]:]", body)
    previous: str | None = None
    for match in tokens:
        token = match.group(0)
        upper = token.upper()
        if upper == "STRUCT" or token in "([":
            depth += 1
        elif upper == "END_STRUCT" or token in ")]":
            depth -= 1
        elif token == ":" and depth == 0 and previous and _IDENT.fullmatch(previous):
            if previous.upper() != "TYPE":
                names.append(previous)
        previous = token
    return names


def split_declarations(path: str, text: str) -> list[Declaration]:
    """Top-level declarations of one file; leading comments go with the next declaration."""
    masked = mask_comments_and_strings(text)
    declarations: list[Declaration] = []
    chunk_start = 0
    position = 0
    while match := _START.search(masked, position):
        kind = match.group(1).upper()
        end = re.compile(rf"\b{END_KEYWORD[kind]}\b", re.IGNORECASE).search(masked, match.end())
        if end is None:
            raise UserError(f"{path}: {kind} without {END_KEYWORD[kind]}")
        body = masked[match.end() : end.start()]
        if kind == "TYPE":
            names = _type_names(body)
        else:
            name = _IDENT.search(body)
            names = [name.group(0)] if name else []
        if not names:
            raise UserError(f"{path}: {kind} without a name")
        declarations.append(Declaration(
            kind=kind, names=names, path=path, text=text[chunk_start : end.end()].strip(),
            uses={token.upper() for token in _IDENT.findall(body)},
        ))
        chunk_start = position = end.end()
    trailing = text[chunk_start:].strip()
    if declarations and trailing:
        declarations[-1].text += "\n" + trailing
    return declarations


def order_declarations(declarations: list[Declaration]) -> list[Declaration]:
    """Dependency order (Kahn), ties by kind then name; raises UserError on duplicates or cycles."""
    owner: dict[str, int] = {}
    for index, declaration in enumerate(declarations):
        for name in declaration.names:
            key = name.upper()
            if key in owner:
                other = declarations[owner[key]]
                raise UserError(f"{name} is declared twice: {other.path} and {declaration.path}")
            owner[key] = index
    depends_on: list[set[int]] = []
    for index, declaration in enumerate(declarations):
        depends_on.append({owner[u] for u in declaration.uses if u in owner and owner[u] != index})
    dependents: list[list[int]] = [[] for _ in declarations]
    for index, needed in enumerate(depends_on):
        for other in needed:
            dependents[other].append(index)
    waiting = [len(needed) for needed in depends_on]
    ready = [(declarations[i].sort_key, i) for i, count in enumerate(waiting) if count == 0]
    heapq.heapify(ready)
    ordered: list[Declaration] = []
    while ready:
        _, index = heapq.heappop(ready)
        ordered.append(declarations[index])
        for dependent in dependents[index]:
            waiting[dependent] -= 1
            if waiting[dependent] == 0:
                heapq.heappush(ready, (declarations[dependent].sort_key, dependent))
    if len(ordered) != len(declarations):
        stuck = sorted(declarations[i].names[0] for i, count in enumerate(waiting) if count)
        raise UserError(f"circular dependency between: {', '.join(stuck)}")
    return ordered


def bundle_sources(root: Path = ROOT) -> list[Path]:
    """The library (OpenPLC shim only) and the application, in path order."""
    library = root / LIBRARY_DIR
    files: list[Path] = []
    for path in sorted(library.rglob("*.st")) if library.is_dir() else []:
        parts = path.relative_to(library).parts
        if len(parts) > 1 and parts[0] == SHIM_DIR and parts[1] != OPENPLC_SHIM:
            continue
        files.append(path)
    app = root / APP_DIR
    files += sorted(app.glob("*.st")) if app.is_dir() else []
    return files


def bundle_declarations(root: Path = ROOT) -> list[Declaration]:
    declarations: list[Declaration] = []
    for path in bundle_sources(root):
        relative = path.relative_to(root).as_posix()
        declarations += split_declarations(relative, path.read_text(encoding="utf-8"))
    return order_declarations(declarations)


def render(declarations: list[Declaration]) -> str:
    counts = {kind: sum(d.kind == kind for d in declarations) for kind in KIND_RANK}
    summary = ", ".join(f"{n} {kind}" for kind, n in counts.items() if n)
    files = sorted({d.path for d in declarations})
    header = [
        "(* ThermoST bundle for OpenPLC v3: library, application and CONFIGURATION in one file.",
        "   Generated by `thermost bundle -o FILE.st`; edit the sources, not this file.",
        f"   {len(declarations)} declarations ({summary}) from {len(files)} files:",
        *(f"     {name}" for name in files),
        "*)",
    ]
    parts = ["\n".join(header)]
    for declaration in declarations:
        parts.append(f"(* ---- {declaration.path} *)\n{declaration.text}")
    return "\n\n".join(parts) + "\n"


def bundle_text(root: Path = ROOT) -> str:
    """The single-file program to upload to OpenPLC (deterministic)."""
    return render(bundle_declarations(root))


_TASK_INTERVAL = re.compile(r"(INTERVAL\s*:=\s*T#)(\d+)(ms)", re.IGNORECASE)


def with_speed(text: str, speed: int) -> str:
    """Shorten every TASK INTERVAL by `speed` (the controllers keep their configured cycle time, so the
    plant behind a real-time harness runs `speed` times faster than the wall clock)."""
    if speed < 1:
        raise UserError(f"--speed must be a whole number >= 1, not {speed}")

    def shorten(m: re.Match) -> str:
        ms = int(m.group(2))
        if ms % speed:
            raise UserError(f"--speed {speed}: TASK interval {ms} ms is not a multiple of it")
        return f"{m.group(1)}{ms // speed}{m.group(3)}"

    out, n = _TASK_INTERVAL.subn(shorten, text)
    if speed != 1 and n == 0:
        raise UserError("--speed: no TASK INTERVAL written in milliseconds (T#...ms) to shorten")
    return out


def main_bundle(args: argparse.Namespace) -> int:
    declarations = bundle_declarations()
    if not declarations:
        raise UserError(f"nothing to bundle: no .st files under {LIBRARY_DIR}/ or {APP_DIR}/")
    text = with_speed(render(declarations), int(getattr(args, "speed", 1) or 1))
    output = writable_file(args.output)
    try:
        output.parent.mkdir(parents=True, exist_ok=True)
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UserError(f"{output}: cannot write: {exc.strerror or exc}") from None
    configurations = [d for d in declarations if d.kind == "CONFIGURATION"]
    if len(configurations) != 1:
        sys.stderr.write(f"thermost: warning: {len(configurations)} CONFIGURATIONs in the bundle "
                         "(OpenPLC needs exactly one)\n")
    print(f"wrote {output}: {len(declarations)} declarations, {len(text.splitlines())} lines")
    return 0
