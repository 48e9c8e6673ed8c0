"""Run a conformance case of ../shared/conformance in the soft-PLC and compare raw words."""

from __future__ import annotations

import json
import os
import struct
from pathlib import Path

from plc.st.compiler import load_application
from plc.st.words import to_words


def shared_dir() -> Path | None:
    env = os.environ.get("THERMOST_SHARED")
    candidates = [Path(env)] if env else []
    root = Path(__file__).resolve().parents[1]
    candidates += [root.parent / "shared", root / "shared"]
    for c in candidates:
        if (c / "conformance").is_dir():
            return c
    return None


def _ordered(words: list[int], bits: int) -> int:
    raw = 0
    for w in words:
        raw = (raw << 16) | w
    sign = raw >> (bits - 1)
    mag = raw & ((1 << (bits - 1)) - 1)
    return -mag if sign else mag


def _is_nan(words: list[int]) -> bool:
    if len(words) == 2:
        return (
            struct.unpack(">f", struct.pack(">HH", *words))[0]
            != struct.unpack(">f", struct.pack(">HH", *words))[0]
        )
    v = struct.unpack(">d", struct.pack(">HHHH", *words))[0]
    return v != v


def run_case(st_path: Path) -> tuple[list[str], list[str]]:
    """Return (failures, quirk mismatches)."""
    expected = json.loads(st_path.with_suffix("").with_suffix(".expected.json").read_text())
    app = load_application([(str(st_path), st_path.read_text())])
    for _ in range(expected["scans"]):
        app.scan()
    by_loc = {v.location: v for v in app.located}
    failures, quirks = [], []
    done = by_loc.get(expected["done_flag"]["location"])
    if done is None or not done.get():
        failures.append("done flag not set")
    for r in expected["results"]:
        var = by_loc.get(r["location"])
        if var is None:
            failures.append(f"{r['var']}: no located variable at {r['location']}")
            continue
        got = to_words(var.get(), r["iec_type"], r["modbus"]["count"])
        want = r["raw"]
        mode = r.get("compare", "exact")
        ok = got == want
        if not ok and mode == "ulp1":
            ok = abs(_ordered(got, 16 * len(got)) - _ordered(want, 16 * len(want))) <= 1
        if not ok and mode == "nan":
            ok = _is_nan(got)
        if not ok:
            msg = (
                f"{r['var']} ({r['iec_type']}, {mode}): got {got} = {var.get()!r}, "
                f"want {want} = {r.get('value')!r}"
            )
            (quirks if mode == "quirk" else failures).append(msg)
    return failures, quirks
