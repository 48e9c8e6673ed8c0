"""Cases that only widen a sweep (more noise draws, more plant variants, every fault on every plant) run with
THERMOST_SLOW=1. Without it they are skipped with the reason printed, so the suite keeps to its CI time while
one case of each sweep still runs."""

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
