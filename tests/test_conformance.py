"""The soft-PLC reproduces every case recorded on the real OpenPLC runtime (../shared/conformance)."""

from __future__ import annotations

import pytest

from tests.conformance_runner import run_case, shared_dir

SHARED = shared_dir()
CASES = sorted((SHARED / "conformance").glob("*.st")) if SHARED else []


@pytest.mark.skipif(
    SHARED is None, reason="../shared/conformance not found (set THERMOST_SHARED to its parent)"
)
@pytest.mark.parametrize("case", CASES, ids=[c.stem for c in CASES])
def test_conformance_case(case, capsys):
    failures, quirks = run_case(case)
    if quirks:
        with capsys.disabled():
            print(f"\n[{case.stem}] MatIEC quirks not reproduced (reported, not failures):")
            for q in quirks:
                print("   ", q)
    assert not failures, "\n".join(failures)


def test_conformance_folder_present_or_skipped():
    if SHARED is None:
        pytest.skip("../shared/conformance not found: the conformance cases were not run")
    assert CASES, "conformance folder is empty"
