"""Pytest-side helpers: load the st_lib library plus a generated test PROGRAM into the soft-PLC.

The builders live in `plc.library_program` (studies use them too); `load_test_app()` compiles the
library and a program and skips the calling test (with the reason printed) when the soft-PLC is not
available.
"""

from __future__ import annotations

from typing import Any

import pytest

from plc.library_program import (  # noqa: F401 - re-exported for the tests
    CONTROLLER_PROGRAM_BODY,
    CONTROLLER_PROGRAM_DECLS,
    REPO_ROOT,
    ST_LIB,
    ScanDriver,
    build_program,
    controller_program,
    library_files,
    library_sources,
    load_program,
)


def load_test_app(program_text: str, extra: list[tuple[str, str]] | None = None) -> Any:
    try:
        import plc.st.compiler  # noqa: F401
    except ImportError as exc:  # soft-PLC not there yet
        pytest.skip(f"soft-PLC compiler not available: {exc}")
    return load_program(program_text, extra, filename="tests/generated_test_program.st")


def f32(value: float) -> float:
    """Round to IEEE binary32, as REAL values are stored."""
    import struct

    return struct.unpack("f", struct.pack("f", value))[0]


def scan_with(drv: Any, defaults: dict[str, float], inputs: dict[str, float]) -> Any:
    """Set a test program's inputs (the defaults, overridden by `inputs`), run one scan, return the driver."""
    for name, value in (defaults | inputs).items():
        drv.set(name, value)
    drv.scan()
    return drv
