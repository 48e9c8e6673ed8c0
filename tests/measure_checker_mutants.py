"""Seeded type errors in the library: how many `thermost check` reports on the mutated line.

Every `N.0` literal in code rewritten as `N`, and every INT/REAL conversion call dropped, one at a
time, in `st_lib/` + `plc/` checked together as one program. Prints the counts and every miss.
Run with `make checker-mutants` (a few minutes); docs/checker.md quotes its output.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from test_checker import ROOT, _mutants, project_st_files  # noqa: E402

from plc.checker import check_sources  # noqa: E402
from plc.checker.lexical import scan  # noqa: E402


def main() -> int:
    sources = [(str(p.relative_to(ROOT)), p.read_text(encoding="utf-8")) for p in project_st_files()]
    counts: dict[str, list[int]] = {}
    missed: list[str] = []
    for i, (name, text) in enumerate(sources):
        for kind, mutants in _mutants(text, scan(text).code).items():
            for line, mutated in mutants:
                run = [*sources[:i], (name, mutated), *sources[i + 1 :]]
                hit = any(d.filename == name and d.line == line for d in check_sources(run))
                count = counts.setdefault(kind, [0, 0])
                count[0] += hit
                count[1] += 1
                if not hit:
                    missed.append(f"{name}:{line}: {kind}: {mutated.splitlines()[line - 1].strip()}")
        print(f"\r{i + 1}/{len(sources)} files", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    for kind, (found, seeded) in counts.items():
        print(f"{kind}: {found} of {seeded} reported on the mutated line")
    print("\n".join(missed) if missed else "no misses")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
