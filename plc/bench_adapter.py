"""Scan cost of FB_FuzzyGainAdapter in the soft-PLC (`thermost bench` calls `run(quick)`).

One PROGRAM per mode calls the adapter once per scan with a moving actual value (so E and EC sweep
the universe); the same program without the adapter call is the baseline that is subtracted. Printed
per mode: CPU microseconds per adapter call and its share of a 10 ms cycle, in the soft-PLC (a Python
interpreter of the ST; a compiled PLC is one to two orders of magnitude faster).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from plc.library_program import library_sources

CYCLE_BUDGET_US = 10_000.0  # a 10 ms PLC cycle
SCANS_FULL = 2000
SCANS_QUICK = 300
WARMUP_SCANS = 120  # > query-table build time (169 nodes / 4 per cycle)
BENCH_CONFIGURATION = (  # runs the benchmark's PROGRAM P_Bench as instance inst0
    "CONFIGURATION Config0\n  RESOURCE Res0 ON PLC\n"
    "    TASK task0(INTERVAL := T#10ms, PRIORITY := 0);\n    PROGRAM inst0 WITH task0 : P_Bench;\n"
    "  END_RESOURCE\nEND_CONFIGURATION\n"
)


@dataclass(frozen=True)
class Mode:
    label: str
    settings: str  # ST statements run once before the first adapter call


MODES = (
    Mode("rule inference, triangular, centroid (61 pts)", ""),
    Mode("rule inference, Gaussian, centroid (all 49 rules fire)", "sFz.eMembership := eFUZZY_MF_GAUSSIAN;"),
    Mode("rule inference, mixed (seed 003, U = 4), centroid",
         "sFz.eMembership := eFUZZY_MF_MIXED; sFz.fUniverse := 4.0;"),
    Mode("rule inference, triangular, weighted average", "sFz.eDefuzz := eFUZZY_DEFUZZ_WEIGHTED;"),
    Mode("query table (13x13, bilinear) + explain", "sFz.bQueryTable := TRUE;"),
    Mode("query table (13x13, bilinear), no explain",
         "sFz.bQueryTable := TRUE; sFz.bExplainInQueryMode := FALSE;"),
)


def program(settings: str, with_adapter: bool) -> str:
    call = ("  fbAd(bEnable := TRUE, fW := 60.0, fX := fX, sCtrlParam := sCtrl, sFuzzyParam := sFz);\n"
            if with_adapter else "")
    return (
        "PROGRAM P_Bench\n  VAR\n    sCtrl : ST_ControllerParameter;\n    sFz : ST_FuzzyParameter;\n"
        "    fbAd : FB_FuzzyGainAdapter;\n    bInit : BOOL;\n    bOk : BOOL;\n    fX : REAL := 59.0;\n"
        "    fPhase : REAL;\n  END_VAR\n"
        "  IF NOT bInit THEN\n"
        "    bOk := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_TEXTBOOK, sRules := sFz.sRules);\n"
        f"    {settings}\n    bInit := TRUE;\n  END_IF;\n"
        "  fPhase := fPhase + 0.01;\n  fX := 60.0 - 0.6 * SIN(fPhase);\n"
        f"{call}END_PROGRAM\n\n" + BENCH_CONFIGURATION
    )


def scan_times(text: str, scans: int, warmup: int = WARMUP_SCANS) -> tuple[float, float, object]:
    """CPU microseconds per scan of the benchmark program after `warmup` scans, its longest single scan
    (one-off work: a plan, a fit), and the application."""
    from plc.st.compiler import load_application

    app = load_application(library_sources() + [("bench_program.st", text)])
    for _ in range(warmup):
        app.scan()
    longest = total = 0
    for _ in range(scans):
        start = time.process_time_ns()
        app.scan()
        took = time.process_time_ns() - start
        total += took
        longest = max(longest, took)
    return total / scans / 1e3, longest / 1e3, app


def time_scans(text: str, scans: int, warmup: int = WARMUP_SCANS) -> tuple[float, object]:
    """CPU microseconds per scan of the benchmark program after `warmup` scans, and the application."""
    mean, _, app = scan_times(text, scans, warmup)
    return mean, app


def adapter_costs(quick: bool) -> list[tuple[str, float | None, str]]:
    """(mode, microseconds per adapter call or None, status) for every mode."""
    scans = SCANS_QUICK if quick else SCANS_FULL
    rows: list[tuple[str, float | None, str]] = []
    for mode in MODES:
        try:
            base_us, _ = time_scans(program(mode.settings, with_adapter=False), scans)
            total_us, app = time_scans(program(mode.settings, with_adapter=True), scans)
        except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
            rows.append((mode.label, None, f"not measured ({type(exc).__name__}: {exc})"))
            continue
        status = f"error {app.get('inst0.fbAd.nErrorId')}" if app.get("inst0.fbAd.bError") else "ok"
        rows.append((mode.label, max(total_us - base_us, 0.0), status))
    return rows


def cost_line(label: str, cost_us: float, note: str = "") -> str:
    """One benchmark row: microseconds per call and the share of a 10 ms cycle."""
    return f"  {label:<58} {cost_us:8.1f} us/call  ({cost_us / CYCLE_BUDGET_US * 100:5.2f} % of 10 ms){note}"


def run(quick: bool) -> None:
    scans = SCANS_QUICK if quick else SCANS_FULL
    print(f"FB_FuzzyGainAdapter scan cost in the soft-PLC ({scans} scans per mode, baseline subtracted)")
    for label, cost, status in adapter_costs(quick):
        if cost is None:
            print(f"  {label}: {status}")
            continue
        print(cost_line(label, cost, f"  [{status}]"))


if __name__ == "__main__":
    run(quick=False)
