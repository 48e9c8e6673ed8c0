"""Soft-PLC core beyond the conformance corpus: features, runtime faults, diagnostics."""

from __future__ import annotations

from pathlib import Path

import pytest

from plc.st.compiler import load_application, typecheck
from plc.st.diagnostics import StError
from plc.st.errors import PlcRuntimeError

HERE = Path(__file__).parent / "st"


def _load(name: str):
    path = HERE / name
    return load_application([(str(path), path.read_text())])


def _prog(body: str, decls: str = "", extra: str = "", interval: str = "T#10ms"):
    text = f"""{extra}
PROGRAM P
  VAR
{decls}
  END_VAR
{body}
END_PROGRAM
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK task0(INTERVAL := {interval}, PRIORITY := 0);
    PROGRAM inst0 WITH task0 : P;
  END_RESOURCE
END_CONFIGURATION
"""
    return load_application([("t.st", text)])


def test_features_program_runs_scan_by_scan():
    app = _load("softplc_features.st")
    assert app.interval_ns == 100_000_000
    app.scan()
    by_name = {v.name: v for v in app.located}
    assert set(by_name) == {"nA", "fB", "bX", "nC", "nI"}  # declared spelling kept for the register map
    assert by_name["fB"].get() == -0.25  # FC_Split(2.75): 2.75 - REAL_TO_DINT(2.75)
    assert by_name["nC"].get() == 3  # VAR_OUTPUT of a FUNCTION through =>
    assert by_name["nI"].get() == 4 + 100  # REPEAT with CONTINUE still checks UNTIL; VAR_IN_OUT INT counted
    assert app.get("inst0.sP.n") == 3  # VAR_IN_OUT STRUCT modified in place, VAR_EXTERNAL global read
    assert app.get("inst0.acc.fSum") == 1.0
    app.scan()
    assert app.get("inst0.sP.n") == 6
    assert app.time_ns == 200_000_000


def test_loading_the_same_sources_again_compiles_once_and_shares_no_state(monkeypatch):
    import plc.st.compiler as compiler

    compiles = []
    original = compiler.compile_to_python
    monkeypatch.setattr(compiler, "compile_to_python", lambda src: compiles.append(src) or original(src))
    compiler._compiled.cache_clear()
    first, second = _load("softplc_features.st"), _load("softplc_features.st")
    assert len(compiles) == 1
    for _ in range(3):
        first.scan()
    assert first.get("inst0.sP.n") == 9
    assert second.get("inst0.sP.n") == 0 and second.time_ns == 0  # its own instances, globals and clock
    second.scan()
    assert second.get("inst0.sP.n") == 3
    assert [v.location for v in first.located] == [v.location for v in second.located]
    assert {v.name: v.get() for v in second.located} != {v.name: v.get() for v in first.located}
    _prog("x := x + 1;", "x : INT;")
    assert len(compiles) == 2  # other sources compile on their own


def test_array_index_fault_stops_program_not_process():
    app = _load("softplc_features.st")
    for _ in range(5):
        app.scan()
    with pytest.raises(PlcRuntimeError) as exc:
        app.scan()  # arr[nA] with nA = 6 on ARRAY[1..5]
    assert exc.value.kind == "index"
    assert app.fault is exc.value
    t = app.time_ns
    app.scan()  # a faulted program does not run and PLC time stands still
    assert app.time_ns == t
    app.reset_fault()


def test_integer_division_by_zero_is_a_fault():
    app = _prog("n := 10 / d;", "n : DINT; d : DINT;")
    with pytest.raises(PlcRuntimeError) as exc:
        app.scan()
    assert exc.value.kind == "divzero"


def test_mod_zero_is_zero_and_real_division_by_zero_is_inf():
    app = _prog("m := 7 MOD d; r := 1.0 / z;", "m : DINT; d : DINT; r : REAL; z : REAL;")
    app.scan()
    assert app.get("inst0.m") == 0
    assert app.get("inst0.r") == float("inf")


def test_type_errors_are_reported_like_matiec():
    path = HERE / "type_errors.st"
    diags = typecheck([(str(path), path.read_text())])
    lines = {d.line: d.message for d in diags}
    assert "INT to DINT" in lines[9]
    assert "integer literal to REAL" in lines[10]
    assert "INT to REAL" in lines[11]
    assert "REAL * INT" in lines[12]
    assert "DINT + INT" in lines[13]
    assert "REAL to LREAL" in lines[14]
    assert "INT to BOOL" in lines[15]
    assert "integer literal" in lines[16]
    assert "not declared" in lines[17]
    assert "real literal" in lines[18]
    assert all(str(d).startswith(f"{path}:{d.line}:{d.col}: ") for d in diags)


def test_syntax_error_is_one_line_per_error_without_traceback():
    with pytest.raises(StError) as exc:
        load_application([("broken.st", "PROGRAM P\nVAR x : INT; END_VAR\nx := ;\nEND_PROGRAM\n")])
    text = str(exc.value)
    assert text.startswith("broken.st:3:")
    assert "Traceback" not in text


def test_time_literals_follow_matiec_long_double_truncation():
    app = _prog(
        "a := T#0.3s; b := T#300ms; c := T#16ms; d := T#1s_500ms; e := T#1h2m3s4ms;",
        "a : TIME; b : TIME; c : TIME; d : TIME; e : TIME;",
    )
    app.scan()
    assert app.get("inst0.a") == 299_999_999
    assert app.get("inst0.b") == 300_000_000
    assert app.get("inst0.c") == 15_999_999
    assert app.get("inst0.d") == 1_500_000_000
    assert app.get("inst0.e") == 3_723_004_000_000


def test_two_tasks_run_at_their_own_intervals():
    text = """
PROGRAM PA VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
PROGRAM PB VAR n : DINT; END_VAR n := n + 1; END_PROGRAM
CONFIGURATION C
  RESOURCE R ON PLC
    TASK fast(INTERVAL := T#10ms, PRIORITY := 0);
    TASK slow(INTERVAL := T#25ms, PRIORITY := 1);
    PROGRAM a WITH fast : PA;
    PROGRAM b WITH slow : PB;
  END_RESOURCE
END_CONFIGURATION
"""
    app = load_application([("tasks.st", text)])
    assert app.interval_ns == 5_000_000  # greatest common divisor, as OpenPLC
    for _ in range(10):
        app.scan()
    assert app.get("a.n") == 5
    assert app.get("b.n") == 2


def test_real_literal_is_double_until_stored():
    app = _prog(
        "eq_lit := a = 0.1; eq_typed := a = REAL#0.1; x := a * a * 10.0; y := 10.0 * a * a;",
        "a : REAL := 0.1; eq_lit : BOOL; eq_typed : BOOL; x : REAL; y : REAL;",
    )
    app.scan()
    assert app.get("inst0.eq_lit") is False
    assert app.get("inst0.eq_typed") is True


def test_references_dates_strings_and_pragmas():
    app = _prog(
        """rX := REF(nX); bValid := rX <> NULL; nY := rX^;
  sB := LEFT(CONCAT(sA, 'def'), 4);
  {{ /* OpenPLC C pass-through: ignored by the soft-PLC */ }}
  bLater := dStamp > D#2024-01-01;""",
        """nX : INT := 3; nY : INT; rX : REF_TO INT; bValid : BOOL;
    sA : STRING := 'abc'; sB : STRING; dStamp : DATE := D#2024-01-02; bLater : BOOL;""",
    )
    app.scan()
    assert app.get("inst0.nY") == 3 and app.get("inst0.bValid") is True
    assert app.get("inst0.sB") == "abcd"
    assert app.get("inst0.bLater") is True
    assert app.get("inst0.dStamp") == 1704153600 * 1_000_000_000


def test_null_dereference_is_a_fault():
    app = _prog("nY := rX^;", "nY : INT; rX : REF_TO INT;")
    with pytest.raises(PlcRuntimeError):
        app.scan()


def test_unsupported_constructs_give_diagnostics_not_crashes():
    cases = {
        "FUNCTION F : VOID VAR_INPUT a : INT; END_VAR a := a; END_FUNCTION": "return type",
        "PROGRAM P VAR t : LTIME; END_VAR t := t; END_PROGRAM": "not supported",
    }
    for text, needle in cases.items():
        diags = typecheck([("x.st", text)])
        assert diags and needle in diags[0].message, (text, diags)
