"""The portable library plus one generated PROGRAM, loaded into the soft-PLC for studies and tests.

`library_sources()`: every `st_lib/**/*.st` except the TwinCAT shim, as `(filename, text)`.
`build_program()` wraps declarations and a body into a PROGRAM + CONFIGURATION with one TASK;
`controller_program()` is such a PROGRAM around one FB_TempController (instance `fbUut`, parameters
`sPar`, mode code `nMode`, rule code `nRule`). `ScanDriver` sets and reads variables by path under
the program instance and scans.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

REPO_ROOT = Path(__file__).resolve().parent.parent
ST_LIB = REPO_ROOT / "st_lib"
EXCLUDED_DIRS = ("shim/twincat",)
INSTANCE = "inst0"


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
        f"    PROGRAM {INSTANCE} WITH task0 : {name};\n"
        "  END_RESOURCE\nEND_CONFIGURATION\n"
    )


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


def load_program(
    program_text: str, extra: list[tuple[str, str]] | None = None, filename: str = "generated_program.st"
) -> Any:
    """The library, `extra` sources and the program (named `filename` in diagnostics), compiled and
    loaded into the soft-PLC."""
    from plc.st.compiler import load_application

    sources = library_sources() + (extra or []) + [(filename, program_text)]
    return load_application(sources)


@dataclass
class ScanDriver:
    """Drives a loaded application: set inputs by path under the instance, scan, read outputs."""

    app: Any
    instance: str = INSTANCE

    def path(self, name: str) -> str:
        return f"{self.instance}.{name}"

    def set(self, name: str, value: Any) -> None:
        self.app.set(self.path(name), value)

    def get(self, name: str) -> Any:
        return self.app.get(self.path(name))

    def scan(self, count: int = 1) -> None:
        for _ in range(count):
            self.app.scan()
