"""Checker verdicts against the real MatIEC iec2c (OpenPLC's flags) on every dialect probe.

Set IEC2C to the iec2c binary and IEC2C_LIB to its include folder (OpenPLC's webserver/lib).
Without them the test is skipped with the reason printed. C-FAIL rows (iec2c accepts, g++ refuses
the generated C) are skipped here: they need OpenPLC's C build to show the failure.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROBES = sorted((ROOT / "tests" / "dialect_probes").glob("*.st"))
IEC2C = os.environ.get("IEC2C")
IEC2C_LIB = os.environ.get("IEC2C_LIB")
OPENPLC_FLAGS = ["-f", "-l", "-p", "-r", "-R", "-a"]
C_FAIL_ROWS = {
    "pragma_attr_body",
    "struct_named_init_type",
    "array_of_array",
    "power_operator",
    "ref_to_scalar_write",
}

pytestmark = pytest.mark.realtools


def _iec2c_accepts(path: Path, out_dir: Path) -> tuple[bool, str]:
    cmd = [IEC2C, *OPENPLC_FLAGS]
    if IEC2C_LIB:
        cmd += ["-I", IEC2C_LIB]
    cmd += ["-T", str(out_dir), str(path)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    return proc.returncode == 0, (proc.stdout + proc.stderr).strip()[:300]


@pytest.mark.skipif(not IEC2C, reason="IEC2C not set: checker verdicts were not compared with the real iec2c")
def test_iec2c_verdicts_match_probes(tmp_path: Path) -> None:
    mismatches = []
    for path in PROBES:
        if path.stem in C_FAIL_ROWS:
            continue  # iec2c accepts these; only the g++ build of the generated C fails
        expect = re.search(r"expect: (ACCEPT|REJECT)", path.read_text(encoding="utf-8")).group(1)
        out_dir = tmp_path / path.stem
        out_dir.mkdir()
        accepted, output = _iec2c_accepts(path, out_dir)
        if accepted != (expect == "ACCEPT"):
            mismatches.append(
                f"{path.name}: probe says {expect}, iec2c {'accepts' if accepted else 'refuses'}: {output}"
            )
    assert not mismatches, "\n".join(mismatches)
