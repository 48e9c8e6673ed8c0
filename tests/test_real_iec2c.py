"""Compile what the project ships with the real MatIEC iec2c (OpenPLC's flags) when it is available.

Set IEC2C to the iec2c binary and IEC2C_LIB to its include folder (OpenPLC's webserver/lib, holding
ieclib.txt). Without them the test is skipped with the reason printed.
With OPENPLC_CORE set as well (OpenPLC's webserver/core: lib/ with iec_std_lib.h, and c_blocks.h),
the C that iec2c generates for the bundle is compiled with g++ the way OpenPLC's compile_program.sh
does it (`g++ -std=gnu++11 -I ./lib -c Config0.c / Res0.c -w`): iec2c accepts some constructs whose
C does not compile (the C-FAIL rows of the dialect table).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
IEC2C = os.environ.get("IEC2C")
IEC2C_LIB = os.environ.get("IEC2C_LIB")
OPENPLC_CORE = os.environ.get("OPENPLC_CORE")
OPENPLC_FLAGS = ["-f", "-l", "-p", "-r", "-R", "-a"]

pytestmark = pytest.mark.realtools


def _shipped_units() -> list[tuple[str, str]]:
    from plc.bundle import bundle_text, order_declarations, render, split_declarations

    units = [("thermost_openplc.st", bundle_text())]
    lib_files = sorted(p for p in (ROOT / "st_lib").rglob("*.st") if "twincat" not in p.parts)
    if lib_files:
        # iec2c must meet a TYPE before a STRUCT member or variable uses it (-p covers POUs only),
        # so the library is put in dependency order as the bundle is, not in path order.
        declarations = []
        for path in lib_files:
            declarations += split_declarations(path.name, path.read_text(encoding="utf-8"))
        units.append(("thermost_library_only.st", render(order_declarations(declarations))))
    return units


@pytest.mark.skipif(not IEC2C, reason="IEC2C not set: the real MatIEC compiler check was not run")
@pytest.mark.parametrize("unit", ["thermost_openplc.st", "thermost_library_only.st"])
def test_iec2c_accepts_shipped_st(unit, tmp_path):
    units = dict(_shipped_units())
    if unit not in units:
        pytest.skip(f"{unit}: nothing to compile yet")
    src = tmp_path / unit
    src.write_text(units[unit])
    cmd = [IEC2C, *OPENPLC_FLAGS]
    if IEC2C_LIB:
        cmd += ["-I", IEC2C_LIB]
    cmd += ["-T", str(tmp_path), str(src)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"iec2c exit {proc.returncode}:\n{proc.stdout}\n{proc.stderr}"


@pytest.mark.skipif(not (IEC2C and OPENPLC_CORE), reason="IEC2C or OPENPLC_CORE not set: g++ build not run")
def test_generated_c_of_bundle_compiles_with_gpp(tmp_path):
    gpp = shutil.which("g++")
    if gpp is None:
        pytest.skip("g++ not found: the generated C was not compiled")
    src = tmp_path / "thermost_openplc.st"
    src.write_text(dict(_shipped_units())["thermost_openplc.st"])
    cmd = [IEC2C, *OPENPLC_FLAGS, *(["-I", IEC2C_LIB] if IEC2C_LIB else []), "-T", str(tmp_path), str(src)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"iec2c exit {proc.returncode}:\n{proc.stdout}\n{proc.stderr}"
    include = Path(OPENPLC_CORE) / "lib"
    for unit in ("Config0.c", "Res0.c"):  # Res0.c includes POUS.c: every POU is compiled
        build = [gpp, "-std=gnu++11", "-I", str(include), "-c", unit, "-w"]
        proc = subprocess.run(build, cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, f"g++ {unit} exit {proc.returncode}:\n{proc.stderr[-3000:]}"
