"""Pytest-side helpers: load the st_lib library plus a generated test PROGRAM into the soft-PLC.

`library_sources()` returns the portable library (every `st_lib/**/*.st` except the TwinCAT shim) as
`(filename, text)` pairs. `build_program()` wraps declarations and a body
into a PROGRAM + CONFIGURATION with one TASK. `load_test_app()` compiles both with the soft-PLC and
skips the calling test (with the reason printed) when the soft-PLC is not available yet.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

REPO_ROOT = Path(__file__).resolve().parent.parent
ST_LIB = REPO_ROOT / "st_lib"
EXCLUDED_DIRS = ("shim/twincat",)
TEST_INSTANCE = "inst0"


def library_files() -> list[Path]:
    files = []
    for path in sorted(ST_LIB.rglob("*.st")):
        rel = path.relative_to(ST_LIB).as_posix()
        if any(rel.startswith(d + "/") for d in EXCLUDED_DIRS):
            continue
        files.append(path)
    return files


def library_sources() -> list[tuple[str, str]]:
    return [(str(p.relative_to(REPO_ROOT)), p.read_text()) for p in library_files()]


def build_program(declarations: str, body: str, interval_ms: int = 100, name: str = "P_Test") -> str:
    """A PROGRAM with the given VAR block content and body, plus its CONFIGURATION."""
    return (
        f"PROGRAM {name}\n  VAR\n{declarations}\n  END_VAR\n{body}\nEND_PROGRAM\n\n"
        "CONFIGURATION Config0\n  RESOURCE Res0 ON PLC\n"
        f"    TASK task0(INTERVAL := T#{interval_ms}ms, PRIORITY := 0);\n"
        f"    PROGRAM {TEST_INSTANCE} WITH task0 : {name};\n"
        "  END_RESOURCE\nEND_CONFIGURATION\n"
    )


def load_test_app(program_text: str, extra: list[tuple[str, str]] | None = None) -> Any:
    try:
        from plc.st.compiler import load_application
    except ImportError as exc:  # soft-PLC not there yet
        pytest.skip(f"soft-PLC compiler not available: {exc}")
    sources = library_sources() + (extra or []) + [("tests/generated_test_program.st", program_text)]
    return load_application(sources)


@dataclass
class ScanDriver:
    """Drives a loaded test application: set inputs by path under the instance, scan, read outputs."""

    app: Any
    instance: str = TEST_INSTANCE

    def path(self, name: str) -> str:
        return f"{self.instance}.{name}"

    def set(self, name: str, value: Any) -> None:
        self.app.set(self.path(name), value)

    def get(self, name: str) -> Any:
        return self.app.get(self.path(name))

    def scan(self, count: int = 1) -> None:
        for _ in range(count):
            self.app.scan()


def f32(value: float) -> float:
    """Round to IEEE binary32, as REAL values are stored."""
    import struct

    return struct.unpack("f", struct.pack("f", value))[0]


CONTROLLER_PROGRAM_DECLS = """    sPar : ST_ControllerParameter;
    fbUut : FB_TempController;
    nMode : INT;
    nModeRejected : BOOL;
    nRule : INT;
    nState : INT;
    nTuneState : INT;
    nRuleUsed : INT;"""

CONTROLLER_PROGRAM_BODY = """  fbUut.eCtrlMode := FC_CtrlModeFromInt(nMode := nMode,
    eLastValid := fbUut.eCtrlMode, bRejected => nModeRejected);
  sPar.eTuneRule := FC_TuneRuleFromInt(nRule := nRule, eLastValid := sPar.eTuneRule);
  fbUut(sParam := sPar);
  nState := FC_CtrlStateToInt(eState := fbUut.eCtrlState);
  nTuneState := FC_CtrlTuneStateToInt(eTuneState := fbUut.eTuneState);
  nRuleUsed := FC_TuneRuleToInt(eRule := sPar.eTuneRuleUsed);"""


def controller_program() -> str:
    """A PROGRAM driving one FB_TempController (instance `fbUut`, parameters `sPar`, mode code `nMode`)."""
    return build_program(CONTROLLER_PROGRAM_DECLS, CONTROLLER_PROGRAM_BODY)
