"""Scan cost of FB_CtrlHeatUp in the soft-PLC (`thermost bench` calls `run(quick)`).

One PROGRAM calls the block once per scan on seed 003's model with X rising like the model's limit-step
response (so the rise detection, the slope filters and the seen-T average all run), then resting at the
target, and the next response (the other way) starting every RESTART_SCANS scans; the same program
without the call is the baseline that is subtracted. The same runs with the model taken as four equal
lags (the plan made by bisection at every start, the longer pulse searched for during it, one halving per
call, the lags and gain read from the rise, the second plan) and as two unequal lags (the plan, the line
through the rise and the lags read from it), X then rising as that chain does, and as a chain 30 % faster
(the lags read off the model's, the plan made again on the shortest slow lag within the line's standard
errors). Printed: CPU microseconds per call and its share of a 10 ms cycle, side by side, and the longest
single scan (where a plan or a fit is made), in the soft-PLC (a Python interpreter of the ST; the scan on
a real OpenPLC runtime is in docs/openplc.md).
"""

from __future__ import annotations

from plc.bench_adapter import BENCH_CONFIGURATION, cost_line, scan_times

SCANS_FULL = 2400
SCANS_QUICK = 1200  # two responses each way, so each kind of plan and fit is in the longest scan
RESTART_SCANS = 600  # one response: limit phase and path, then a new target
HOLD_FROM_SCAN = 300  # X rests at the target from here (past the rise a plan on lags measures), so the next
#                      response starts from rest


NLAG_ORDER = 4
TWO_LAG_RATIO = 0.12  # the TCLab's block and sensor lags, 16.7 s / 140 s
FASTER_PLANT = 0.7  # the lags of a plant whose rise is read off the model's, times the model's


def program(with_block: bool, order: int = 1, ratio: float = 0.0, plant_scale: float = 1.0) -> str:
    """X rises as the model the block plans on answers the limit step (seed 003's first-order lag, or the
    n-lag / two-lag chain of its two-point FOPDT), so a plan on lags sees its own model's rise and measures
    it in full."""
    call = ("  fbHu(bEnable := TRUE, fW := fW, fX := fX, fY0 := fY0, fKs := 0.5916, fTu := 10.6,\n"
            f"       fTg := 23.4, nOrder := {order}, fLagRatio := {ratio!r}, fYMin := 0.0, fYMax := 100.0,\n"
            "       fMinStep := 5.0,\n"
            "       fCycleTime := 0.1);\n"
            "  IF fbHu.bActive THEN\n    nActive := nActive + 1;\n  END_IF;\n"
            if with_block else "")
    if order <= 1:
        chain = ""
        rise = "  IF fT > 10.6 THEN\n    fX := 160.0 + 59.16 * (1.0 - EXP(-(fT - 10.6) / 23.4));\n  END_IF;\n"
    else:  # the chain's lags from the FOPDT once; its response each scan
        chain = ("  IF NOT bChain THEN\n"
                 f"    bChain := FC_NLagFromFopdt(nOrder := {order}, fRatio := {ratio!r}, fTu := 10.6,"
                 " fTg := 23.4, fLag => fLag, fDelay => fDelay);\n  END_IF;\n")
        rise = (f"  fX := 160.0 + 59.16 * FC_LagModelStep(fX := (fT - fDelay) / (fLag * {plant_scale!r}),"
                f" nOrder := {order},"
                f" fRatio := {ratio!r});\n")
    return (
        "PROGRAM P_Bench\n  VAR\n    fbHu : FB_CtrlHeatUp;\n    nScan : INT;\n    fT : REAL;\n"
        "    fX : REAL := 160.0;\n    fW : REAL := 160.0;\n    fY0 : REAL;\n    nActive : DINT;\n"
        "    fLag : REAL;\n    fDelay : REAL;\n    bChain : BOOL;\n  END_VAR\n"
        f"{chain}"
        "  nScan := nScan + 1;\n"
        f"  IF nScan >= {RESTART_SCANS} THEN\n    nScan := 0;\n    fW := 360.0 - fW;\n  END_IF;\n"
        "  fT := INT_TO_REAL(nScan) * 0.1;\n"
        "  fX := 160.0;\n"
        f"{rise}"
        f"  IF nScan >= {HOLD_FROM_SCAN} THEN\n    fX := 200.0;\n  END_IF;\n"
        "  fY0 := 0.0;\n"
        "  IF fW < 180.0 THEN\n    fX := 360.0 - fX;\n    fY0 := 67.6;\n  END_IF;\n"
        f"{call}END_PROGRAM\n\n" + BENCH_CONFIGURATION
    )


def heatup_cost(quick: bool, order: int = 1, ratio: float = 0.0, plant_scale: float = 1.0
                ) -> tuple[float, float, float]:
    """Microseconds per FB_CtrlHeatUp call (baseline subtracted), the share of calls with a response, and
    the longest scan with the block (a plan made at a response's start, a fit of the rise)."""
    scans = SCANS_QUICK if quick else SCANS_FULL
    total, longest, app = scan_times(program(True, order, ratio, plant_scale), scans)
    base, _, _ = scan_times(program(False, order, ratio, plant_scale), scans)
    return max(total - base, 0.0), app.get("inst0.nActive") / scans, longest


def run(quick: bool) -> None:
    scans = SCANS_QUICK if quick else SCANS_FULL
    print(f"FB_CtrlHeatUp scan cost in the soft-PLC ({scans} scans, responses restarted every "
          f"{RESTART_SCANS}, baseline subtracted; the longest scan is whole)")
    for order, ratio, scale, label in (
            (1, 0.0, 1.0, "first-order model"), (NLAG_ORDER, 0.0, 1.0, f"{NLAG_ORDER} equal lags"),
            (2, TWO_LAG_RATIO, 1.0, "two unequal lags"),
            (2, TWO_LAG_RATIO, FASTER_PLANT, f"two unequal lags, the plant's {FASTER_PLANT:g} x")):
        try:
            cost, active, longest = heatup_cost(quick, order, ratio, scale)
        except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
            print(f"  not measured ({type(exc).__name__}: {exc})")
            return
        print(cost_line(f"model-based setpoint response on the {label}", cost,
                        f"; a response ran in {active:.0%} of the calls; longest scan {longest:,.0f} us"))


if __name__ == "__main__":
    run(quick=False)
