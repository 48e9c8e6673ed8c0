"""Scan cost of the self-tuner's closing fit, FB_TuneFitNLag, in the soft-PLC (`thermost bench` calls
`run(quick)`).

The fit runs once, in the scan that ends a TUNE: least squares over the whole step record for chains of
1 .. 6 equal lags and for two unequal lags, then the delay searched around the inflection tangent's. One
PROGRAM builds a 64-point record of a plant's step response in its first scan and calls the function once
per scan after that; the same program without the call is the baseline that is subtracted. Two records:
seed 003's hot end (first order, 0.5916 degC/%, T 23.4 s, L 10.6 s) and the TCLab-like heater of two
unequal lags (0.6 degC/%, 140 s and 16.7 s). Printed: CPU milliseconds per call and their share of the
application's 100 ms task, with the model the fit chose: the whole fit in the scan that ends the TUNE
(fTuneFitBudget 0, the default). Then the same fit spread at SPREAD_BUDGET residuals per cycle
(fTuneFitBudget): the cycles it takes and its longest scan, baseline subtracted.
"""

from __future__ import annotations

from dataclasses import dataclass

from plc.bench_adapter import BENCH_CONFIGURATION, library_sources, scan_times, time_scans

CALLS_FULL = 5
CALLS_QUICK = 2
TASK_BUDGET_MS = 100.0  # the application's task interval
HIST_POINTS = 64  # T_TuneHistory
STEP_PCT = 50.0
SPREAD_BUDGET = 300  # residuals of the record per cycle for the spread figure (fTuneFitBudget)
SPREAD_FITS = 2  # whole spread fits timed, scan by scan


@dataclass(frozen=True)
class Record:
    label: str
    gain: float  # degC/%
    lag_s: float
    lag2_s: float  # 0: first order
    delay_s: float
    spacing_s: float  # between history entries
    tangent_delay_s: float  # what the tuner's inflection tangent gives (an input of the fit)


RECORDS = (
    Record("seed 003 hot end (first order)", 0.5916, 23.4, 0.0, 10.6, 1.5, 10.6),
    Record("two unequal lags (140 s, 16.7 s)", 0.6, 140.0, 16.7, 0.5, 4.0, 20.0),
)


def _rise(r: Record) -> str:
    """ST expression of the rise at fT s after the delay (degC)."""
    k = r.gain * STEP_PCT
    if r.lag2_s <= 0.0:
        return f"{k!r} * (1.0 - EXP(-fT / {r.lag_s!r}))"
    t1, t2 = r.lag_s, r.lag2_s
    return (f"{k!r} * (1.0 - ({t1!r} * EXP(-fT / {t1!r}) - {t2!r} * EXP(-fT / {t2!r})) / "
            f"{t1 - t2!r})")


def program(r: Record, with_fit: bool, budget: int = 0) -> str:
    """The record in the first scan, then the fit: a new one whenever the last has ended."""
    call = (f"    fbFit(bStart := NOT fbFit.bBusy, nBudget := {budget}, fTuTangent := {r.tangent_delay_s!r}, "
            "fStart := 0.0, "
            f"fSpacing := {r.spacing_s!r},\n"
            f"          nCount := {HIST_POINTS}, fDeltaY := {STEP_PCT!r}, aHist := aHist);\n"
            "    bOk := fbFit.bOk;\n    fKs := fbFit.fKs;\n    fTu := fbFit.fTu;\n"
            "    nOrder := fbFit.nOrder;\n    fRatio := fbFit.fRatio;\n"
            if with_fit else "")
    return (
        "PROGRAM P_Bench\n  VAR\n    aHist : T_TuneHistory;\n    bFilled : BOOL;\n    nK : INT;\n"
        "    fT : REAL;\n    bOk : BOOL;\n    fKs : REAL;\n    fTu : REAL;\n"
        "    nOrder : INT;\n"
        "    fRatio : REAL;\n    fbFit : FB_TuneFitNLag;\n  END_VAR\n"
        "  IF NOT bFilled THEN\n"
        f"    FOR nK := 0 TO {HIST_POINTS - 1} DO\n"
        f"      fT := INT_TO_REAL(nK + 1) * {r.spacing_s!r} - {r.delay_s!r};\n"
        "      aHist[nK] := 0.0;\n"
        f"      IF fT > 0.0 THEN\n        aHist[nK] := {_rise(r)};\n      END_IF;\n"
        "    END_FOR;\n    bFilled := TRUE;\n  ELSE\n"
        f"{call}  END_IF;\nEND_PROGRAM\n\n" + BENCH_CONFIGURATION
    )


def fit_cost(r: Record, quick: bool) -> tuple[float, str]:
    """Milliseconds per FB_TuneFitNLag call (baseline subtracted) and the model it chose."""
    calls = CALLS_QUICK if quick else CALLS_FULL
    # one scan first: it builds the record
    total, app = time_scans(program(r, True), calls, warmup=1)
    base, _ = time_scans(program(r, False), calls, warmup=1)
    cost_ms = max(total - base, 0.0) / 1e3
    if not app.get("inst0.bOk"):
        return cost_ms, "no model"
    order, ratio = app.get("inst0.nOrder"), app.get("inst0.fRatio")
    model = f"two lags, ratio {ratio:.2f}" if ratio > 0.0 else f"order {order}"
    fitted = f"{model}, Ks {app.get('inst0.fKs'):.3f} degC/%, Tu {app.get('inst0.fTu'):.1f} s"
    return cost_ms, fitted


def spread_cost(r: Record) -> tuple[int, float]:
    """The cycles one fit takes at SPREAD_BUDGET residuals per cycle, and its longest scan in milliseconds
    (the baseline program's mean scan subtracted)."""
    from plc.st.compiler import load_application

    app = load_application(library_sources() + [("bench_program.st", program(r, True, SPREAD_BUDGET))])
    app.scan()  # the record
    cycles = 1
    app.scan()
    while app.get("inst0.fbFit.bBusy"):
        app.scan()
        cycles += 1
    _, longest, _ = scan_times(program(r, True, SPREAD_BUDGET), SPREAD_FITS * cycles, warmup=1)
    base, _ = time_scans(program(r, False), SPREAD_FITS * cycles, warmup=1)
    return cycles, max(longest - base, 0.0) / 1e3


def run(quick: bool) -> None:
    calls = CALLS_QUICK if quick else CALLS_FULL
    print(f"FB_TuneFitNLag, the fit in the scan that ends a TUNE, in the soft-PLC ({calls} calls per record, "
          "baseline subtracted)")
    for r in RECORDS:
        try:
            cost, model = fit_cost(r, quick)
        except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
            print(f"  {r.label}: not measured ({type(exc).__name__}: {exc})")
            continue
        print(f"  {r.label:<40} {cost:8.1f} ms/call  ({cost / TASK_BUDGET_MS * 100:5.1f} % of a "
              f"{TASK_BUDGET_MS:g} ms task); fitted {model}")
    print(f"the same fit spread at {SPREAD_BUDGET} residuals per cycle (fTuneFitBudget), longest scan:")
    for r in RECORDS:
        try:
            cycles, longest = spread_cost(r)
        except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
            print(f"  {r.label}: not measured ({type(exc).__name__}: {exc})")
            continue
        print(f"  {r.label:<40} {longest:8.1f} ms/scan ({longest / TASK_BUDGET_MS * 100:5.1f} % of a "
              f"{TASK_BUDGET_MS:g} ms task) over {cycles} cycles")


if __name__ == "__main__":
    run(quick=False)
