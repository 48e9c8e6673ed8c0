"""`thermost check`: dialect probes, conformance corpus and library stay clean, CLI contract."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from plc.checker import check_sources
from plc.cli import main

ROOT = Path(__file__).resolve().parents[1]
PROBES = sorted((ROOT / "tests" / "dialect_probes").glob("*.st"))
HEADER = re.compile(r"\(\* probe: (\w+) \| expect: (ACCEPT|REJECT)(?: \| mention: (.*?))? \*\)")
DIAGNOSTIC_LINE = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): (?P<message>.+)$")


def shared_dir() -> Path | None:
    candidates = [os.environ.get("THERMOST_SHARED"), str(ROOT.parent / "shared"), "/work/shared"]
    for candidate in candidates:
        if candidate and Path(candidate, "reference", "matiec-dialect.md").is_file():
            return Path(candidate)
    return None


def probe_header(path: Path) -> tuple[str, str, str | None]:
    match = HEADER.search(path.read_text(encoding="utf-8"))
    assert match, f"{path.name}: probe header missing"
    return match.group(1), match.group(2), match.group(3)


@pytest.mark.parametrize("path", PROBES, ids=[p.stem for p in PROBES])
def test_probe(path: Path) -> None:
    case, expect, mention = probe_header(path)
    assert case == path.stem
    diagnostics = check_sources([(path.name, path.read_text(encoding="utf-8"))])
    if expect == "ACCEPT":
        assert diagnostics == [], "\n".join(map(str, diagnostics))
    else:
        assert mention, f"{path.name}: a REJECT probe names what the error must mention"
        assert any(mention.lower() in d.message.lower() for d in diagnostics), (
            f"no diagnostic mentions {mention!r}: " + "\n".join(map(str, diagnostics))
        )


def test_every_dialect_row_has_a_probe() -> None:
    shared = shared_dir()
    if shared is None:
        pytest.skip("shared/reference/matiec-dialect.md not found (set THERMOST_SHARED)")
    table = (shared / "reference" / "matiec-dialect.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| ([a-z0-9_]+) \| .*? \| (ACCEPT|REJECT|C-FAIL)", table, re.M)
    assert len(rows) > 100
    probes = {p.stem: probe_header(p)[1] for p in PROBES}
    for case, result in rows:
        assert case in probes, f"dialect row {case} has no probe"
        if result in ("REJECT", "C-FAIL"):
            assert probes[case] == "REJECT", case


def test_conformance_corpus_is_clean() -> None:
    shared = shared_dir()
    if shared is None:
        pytest.skip("shared/conformance not found (set THERMOST_SHARED)")
    files = sorted((shared / "conformance").glob("*.st"))
    assert files
    for path in files:  # each case is its own program
        diagnostics = check_sources([(path.name, path.read_text(encoding="utf-8"))])
        assert diagnostics == [], "\n".join(map(str, diagnostics))


def project_st_files() -> list[Path]:
    """The MatIEC library and application; the TwinCAT shim is for another target."""
    files = [*sorted((ROOT / "st_lib").rglob("*.st")), *sorted((ROOT / "plc").rglob("*.st"))]
    return [p for p in files if "twincat" not in p.parts]


def test_project_st_files_are_clean() -> None:
    files = project_st_files()
    if not files:
        pytest.skip("no .st files in st_lib/ or plc/ yet")
    sources = [(str(p.relative_to(ROOT)), p.read_text(encoding="utf-8")) for p in files]
    diagnostics = check_sources(sources)
    assert diagnostics == [], "\n".join(map(str, diagnostics))


def test_no_project_pou_is_left_out_of_typing() -> None:
    """The lenient index types every POU of the library and application checked together."""
    from plc.st.compiler import analyse
    from plc.st.parser import parse_source

    files = project_st_files()
    if not files:
        pytest.skip("no .st files in st_lib/ or plc/ yet")
    index, _ = analyse([parse_source(p.read_text(encoding="utf-8"), p.name) for p in files])
    assert len(index.pous) > 40
    assert [name for name, pou in index.pous.items() if pou.failed] == []


def test_a_pou_using_an_unknown_type_is_left_out_and_the_others_are_typed() -> None:
    src = """FUNCTION_BLOCK FB_Uses
  VAR
    fbOther : FB_Elsewhere;
    fX : REAL;
  END_VAR
  fX := 1;
END_FUNCTION_BLOCK

PROGRAM P_Own
  VAR
    fY : REAL;
  END_VAR
  fY := 2;
END_PROGRAM
"""
    found = [(d.line, d.message) for d in check_sources([("mixed.st", src)])]
    assert [line for line, _ in found] == [13]
    assert "write a real literal" in found[0][1]


BAD_PROGRAM = """PROGRAM P_Bad
  VAR
    nI : INT;
    fR : REAL;
  END_VAR
  fR := 1; // two errors on this line
  fR := nI * fR;
END_PROGRAM
"""


def test_cli_reports_sorted_lines_and_exit_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.st"
    bad.write_text(BAD_PROGRAM, encoding="utf-8")
    assert main(["check", str(bad)]) == 1
    lines = capsys.readouterr().out.splitlines()
    parsed = [DIAGNOSTIC_LINE.match(line) for line in lines]
    assert all(parsed), lines
    positions = [(int(m["line"]), int(m["col"])) for m in parsed]
    assert positions == sorted(positions)
    assert positions == [(6, 3), (6, 12), (7, 9)]
    assert {m["file"] for m in parsed} == {str(bad)}


def test_cli_clean_file_exit_0(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = tmp_path / "good.st"
    good.write_text(
        BAD_PROGRAM.replace("fR := 1; // two errors on this line", "fR := 1.0;").replace(
            "nI * fR", "INT_TO_REAL(nI) * fR"
        ),
        encoding="utf-8",
    )
    assert main(["check", str(good)]) == 0
    assert capsys.readouterr().out == ""


def test_cli_missing_file_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "nope.st"
    assert main(["check", str(missing)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"{missing}:1:1: cannot read file")


@pytest.mark.parametrize(
    "garbage",
    [
        "PROGRAM",
        "END_IF;;;",
        "FUNCTION_BLOCK FB_X VAR_INPUT a : ; END_VAR a := ((1 + ; END_FUNCTION_BLOCK",
        "TYPE E_X : (A, B END_TYPE PROGRAM P VAR x : E_X; END_VAR x := E_X#; END_PROGRAM",
        "(* unterminated comment",
        "x := 'unterminated string",
        "\x00\x01\x02 binary \xff",
    ],
)
def test_malformed_input_gives_diagnostics_not_tracebacks(garbage: str) -> None:
    diagnostics = check_sources([("g.st", garbage)])
    for d in diagnostics:
        assert DIAGNOSTIC_LINE.match(str(d)) and d.line >= 1 and d.col >= 1


def test_files_checked_together_share_declarations() -> None:
    fb = """FUNCTION_BLOCK FB_Gain
  VAR_INPUT
    fK : REAL;
  END_VAR
  VAR_OUTPUT
    fY : REAL;
  END_VAR
  fY := fK;
END_FUNCTION_BLOCK
"""
    prog = """PROGRAM P_Use
  VAR
    fbGain : FB_Gain;
    nK : INT;
  END_VAR
  fbGain(fK := nK);
END_PROGRAM
"""
    alone = check_sources([("prog.st", prog)])
    assert alone == []  # FB_Gain unknown: nothing is guessed
    together = check_sources([("fb.st", fb), ("prog.st", prog)])
    assert [(d.filename, d.line) for d in together] == [("prog.st", 6)]
    assert "parameter 'fK'" in together[0].message


def test_agrees_with_the_soft_plc_typer_on_its_type_error_file() -> None:
    """The checker (lenient index) and the compiler (strict) flag the same positions."""
    path = ROOT / "tests" / "st" / "type_errors.st"
    compiler = pytest.importorskip("plc.st.compiler")
    if not path.is_file():
        pytest.skip("tests/st/type_errors.st not present")
    sources = [(path.name, path.read_text(encoding="utf-8"))]
    ours = {(d.line, d.col) for d in check_sources(sources)}
    theirs = {(d.line, d.col) for d in compiler.typecheck(sources)}
    assert theirs and ours == theirs


LITERAL_REAL = re.compile(r"(?<![\w.#])(?<!#-)(\d+)\.0(?![\w])")
INT_TO_REAL_CALL = re.compile(r"\b(?:SINT|INT|DINT|UINT|UDINT|LINT)_TO_L?REAL\(")
REAL_CONVERSION_CALL = re.compile(
    r"\b(?:REAL_TO_LREAL|LREAL_TO_REAL|L?REAL_TO_(?:SINT|INT|DINT|LINT|UINT|UDINT))\("
)


def _mutants(text: str, code: list[bool]) -> dict[str, list[tuple[int, str]]]:
    """(line, mutated text) per kind of seeded type error."""
    out: dict[str, list[tuple[int, str]]] = {"real literal written as integer": [], "conversion dropped": []}
    for m in LITERAL_REAL.finditer(text):
        if code[m.start()]:
            out["real literal written as integer"].append(
                (text.count("\n", 0, m.start()) + 1, text[: m.start()] + m.group(1) + text[m.end() :])
            )
    for pattern in (INT_TO_REAL_CALL, REAL_CONVERSION_CALL):
        for m in pattern.finditer(text):
            if code[m.start()]:
                out["conversion dropped"].append(
                    (text.count("\n", 0, m.start()) + 1, text[: m.start()] + "(" + text[m.end() :])
                )
    return out


def test_seeded_type_errors_in_the_corpus_are_found() -> None:
    """Mutation check: seeded MatIEC type errors in known-good programs are reported on their line, every
    one (iec2c refuses an integer literal among real ones even in MAX(1, 10.0) or 1 + 0.5)."""
    from plc.checker.lexical import scan

    shared = shared_dir()
    if shared is None:
        pytest.skip("shared/conformance not found (set THERMOST_SHARED)")
    counts: dict[str, list[int]] = {}
    unexplained: list[str] = []
    for path in sorted((shared / "conformance").glob("*.st"))[::2]:  # half the corpus keeps it fast
        text = path.read_text(encoding="utf-8")
        for kind, mutants in _mutants(text, scan(text).code).items():
            for line, mutated in mutants:
                hit = any(d.line == line for d in check_sources([(path.name, mutated)]))
                counts.setdefault(kind, [0, 0])
                counts[kind][0] += hit
                counts[kind][1] += 1
                source_line = mutated.splitlines()[line - 1]
                if not hit:
                    unexplained.append(f"{path.name}:{line}: {kind}: {source_line.strip()}")
    print("seeded type errors (found, seeded):", counts)
    assert counts["conversion dropped"][1] > 10 and counts["real literal written as integer"][1] > 30
    assert not unexplained, "\n".join(unexplained)


def test_positions_are_tree_sitter_byte_columns_with_non_ascii_text() -> None:
    src = (
        "PROGRAM P_X\n  VAR\n    n : INT;\n  END_VAR\n"
        "  n := n + 1; // °C\n  (* °C *) n := n + 1.5; {attribute}\nEND_PROGRAM\n"
    )
    found = [(d.line, d.col, d.message.split(" ")[0].lower()) for d in check_sources([("u.st", src)])]
    # line 6: '  (* °C *) n := ' is 17 bytes (° is 2), so the expression starts at byte column 18
    assert found == [(5, 15, "line"), (6, 18, "data"), (6, 27, "pragma")]


def test_cli_directory_argument(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "bad.st").write_text(BAD_PROGRAM, encoding="utf-8")
    (tmp_path / "notes.txt").write_text("fR := 1; // not ST", encoding="utf-8")
    assert main(["check", str(tmp_path)]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines and all(line.startswith(str(tmp_path / "sub" / "bad.st") + ":") for line in lines)


def test_openplc_bundle_is_clean() -> None:
    """The single file uploaded to OpenPLC (`thermost bundle`) passes the checker."""
    bundle = pytest.importorskip("plc.bundle")
    text = bundle.bundle_text()
    diagnostics = check_sources([("thermost_openplc.st", text)])
    assert diagnostics == [], "\n".join(map(str, diagnostics[:20]))
