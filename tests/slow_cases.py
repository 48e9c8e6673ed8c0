"""What CI leaves to THERMOST_SLOW=1, in one place. Cases that only widen a sweep (more noise draws, more
plant variants, every fault on every plant) are skipped with the reason printed, so the suite keeps to its
CI time while one case of each sweep still runs; a closed-loop goal known not to be met yet is skipped with
its figures, and runs as its file's strict expected failure with THERMOST_SLOW=1."""

from __future__ import annotations

import os

import pytest

SLOW_ENV = "THERMOST_SLOW"


def slow_enabled() -> bool:
    return bool(os.environ.get(SLOW_ENV))


def skip_unless_slow(what: str) -> None:
    """Skip the calling test in CI, naming the case and how to run it."""
    if not slow_enabled():
        pytest.skip(f"{what}: extra closed-loop run (CI time); set {SLOW_ENV}=1")


def skip_known_shortfall(label: str, why: str) -> None:
    """A goal not met yet: skipped in CI with the reason; with THERMOST_SLOW=1 the test runs, marked by its
    file as a strict expected failure."""
    if not slow_enabled():
        pytest.skip(f"known shortfall, {label}: {why} ({SLOW_ENV}=1 runs it as an expected failure)")
