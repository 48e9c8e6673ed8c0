"""FB_HeatUpNLagLatePlan and FC_HeatUpNLagLateLands: the longer first pulse of a model-based setpoint response
on n equal lags, landed by the brake of the second plan made where the rise passes its second point,
against the same response evaluated densely in double precision. The shares are the bench oven's
100 -> 150 degC step (four lags of 45 s, 2.2 degC/%, 25 degC ambient: 34.1 % holds 100 degC, 56.8 % holds
150 degC, the heater's limits 0 and 100 %)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app, scan_with
from tests.test_lib_heatup import (
    OVEN_AMBIENT,
    OVEN_K,
    OVEN_L,
    OVEN_N,
    OVEN_T,
    OVEN_W0,
    OVEN_W1,
    oven_unit_step,
)

Y0, YH = (OVEN_W0 - OVEN_AMBIENT) / OVEN_K, (OVEN_W1 - OVEN_AMBIENT) / OVEN_K  # holding powers, %
L_TOWARD, L_AWAY = (100.0 - Y0) / (YH - Y0), (0.0 - Y0) / (YH - Y0)  # the heater's limits 100 and 0 %
X_START = -OVEN_L / OVEN_T
RISE_SECOND = 0.4  # the second point: twice the first, which is a fifth of the step
PEAK_SHARE = 0.0025
A_MAX = 3.0
DENSE_TOL = 2e-4  # the PLC finds peaks on a grid of 61 points and its landing by bisection in REAL

DECLS = """    nOrder, nCalls : INT;
    fA, fLToward, fLAway, fXStart, fRiseSecond, fAMax, fXSecond, fBrake, fFirst, fPlan, fReach : REAL;
    fAfterOne : REAL;
    bLands : BOOL;
    fbPlan : FB_HeatUpNLagLatePlan;"""
BODY = """  bLands := FC_HeatUpNLagLateLands(nOrder := nOrder, fA := fA, fLToward := fLToward,
                                   fLAway := fLAway, fXStart := fXStart, fRiseSecond := fRiseSecond,
                                   fAMax := fAMax, fXSecond => fXSecond, fBrake => fBrake);
  fFirst := FC_HeatUpNLagPlan(nOrder := nOrder, fRatio := 0.0, fLToward := fLToward, fLAway := fLAway,
                              fD := 0.0, fB := 0.0, fXStart := fXStart, fAMax := fAMax);
  fbPlan(bStart := TRUE, nOrder := nOrder, fLToward := fLToward, fLAway := fLAway, fAFirst := fFirst,
         fAMax := fAMax, fXStart := fXStart, fRiseSecond := fRiseSecond, fReach := fReach);
  nCalls := 0;
  fAfterOne := fbPlan.fA;
  WHILE fbPlan.bBusy DO
    fbPlan(bStart := FALSE);
    nCalls := nCalls + 1;
    IF nCalls = 1 THEN
      fAfterOne := fbPlan.fA;
    END_IF;
  END_WHILE;
  fPlan := fbPlan.fA;"""
HALVINGS = 8


def response(x: np.ndarray, a: float, c: float = 0.0, e: float = 0.0) -> np.ndarray:
    """L_TOWARD for a lags, the holding power, from c lags after the start L_AWAY for e lags, then the
    holding power again."""
    m = L_TOWARD * oven_unit_step(x) + (1.0 - L_TOWARD) * oven_unit_step(x - a)
    if e > 0.0:
        m += (L_AWAY - 1.0) * oven_unit_step(x - c) + (1.0 - L_AWAY) * oven_unit_step(x - c - e)
    return m


def dense_x(a: float, c: float = 0.0, e: float = 0.0) -> np.ndarray:
    return np.linspace(X_START, max(a, c + e) + 3.0 * OVEN_N + 3.0, 400_001)


def landing(a: float, c: float, e: float, x_from: float) -> tuple[float, float]:
    """Peak of the response from x_from on and its lowest point after that peak."""
    x = dense_x(a, c, e)
    m = response(x, a, c, e)[x >= x_from]
    k = int(np.argmax(m))
    return float(m[k]), float(m[k:].min())


def band_entry(a: float, c: float = 0.0, e: float = 0.0, band: float = 0.02) -> float:
    """When the response last enters the 2 % band, x."""
    x = dense_x(a, c, e)
    out = np.abs(response(x, a, c, e) - 1.0) > band
    return float(x[np.flatnonzero(out)[-1] + 1])


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


def run(fn: ScanDriver, **inputs: float) -> ScanDriver:
    return scan_with(fn, dict(nOrder=OVEN_N, fA=1.0, fLToward=L_TOWARD, fLAway=L_AWAY, fXStart=X_START,
                              fRiseSecond=RISE_SECOND, fAMax=A_MAX, fReach=1.0), inputs)


@pytest.mark.parametrize("a", [0.8, 1.0, 1.2])
def test_the_second_plan_is_made_where_the_rise_passes_its_second_point(fn: ScanDriver, a: float) -> None:
    got = run(fn, fA=a)
    x = dense_x(a)
    crossing = float(x[np.argmax(response(x, a) >= RISE_SECOND)])
    print(f"pulse {a} lags: second point at x {got.get('fXSecond'):.5f} (dense {crossing:.5f}), brake "
          f"{got.get('fBrake'):.4f} lags")
    assert got.get("fXSecond") == pytest.approx(max(crossing, a + X_START), abs=1e-4)


def test_a_rise_past_its_second_point_within_the_pulse_is_braked_where_the_pulse_ends(fn: ScanDriver) -> None:
    a = 2.5
    x = dense_x(a)
    assert float(x[np.argmax(response(x, a) >= RISE_SECOND)]) < a + X_START
    assert run(fn, fA=a).get("fXSecond") == pytest.approx(a + X_START, abs=1e-6)


def test_the_search_makes_one_halving_per_call_and_its_plan_so_far_is_always_usable(fn: ScanDriver) -> None:
    """The pulse may end on the plan so far at any call: it only grows, from the single switch's."""
    got = run(fn, fReach=1.0)
    assert got.get("nCalls") == HALVINGS
    assert got.get("fFirst") <= got.get("fAfterOne") <= got.get("fPlan")
    assert run(fn, fA=got.get("fAfterOne")).get("bLands")


def test_the_longest_pulse_lands_within_the_tolerance_and_one_more_step_does_not(fn: ScanDriver) -> None:
    first = run(fn).get("fFirst")
    full = run(fn, fReach=1.0).get("fPlan")
    assert full > first
    got = run(fn, fA=full)
    assert got.get("bLands")
    x2, e = got.get("fXSecond"), got.get("fBrake")
    peak, low = landing(full, x2 - X_START, e, x2)
    print(f"one switch {first:.4f} lags; the longest late-braked pulse {full:.4f} lags, brake {e:.4f} lags "
          f"from x {x2:.4f}: peak {100 * (peak - 1):.3f} %, back to {100 * (low - 1):.3f} %")
    assert e > 0.0
    assert peak <= 1.0 + PEAK_SHARE + DENSE_TOL
    assert low >= 1.0 - PEAK_SHARE - DENSE_TOL
    beyond = full + 2.0 * (A_MAX - first) / 2**HALVINGS  # the search's last bracket, twice over
    assert not run(fn, fA=beyond).get("bLands")


@pytest.mark.parametrize("reach", [0.4, 1.0])
def test_the_late_brake_enters_the_band_sooner_than_one_switch(fn: ScanDriver, reach: float) -> None:
    first = run(fn).get("fFirst")
    a = run(fn, fReach=reach).get("fPlan")
    assert a == pytest.approx(first + reach * (run(fn, fReach=1.0).get("fPlan") - first), rel=1e-5)
    got = run(fn, fA=a)
    x2, e = got.get("fXSecond"), got.get("fBrake")
    one, late = band_entry(first), band_entry(a, x2 - X_START, e)
    print(f"reach {reach}: one switch {first:.4f} lags enters the band at x {one:.3f}; pulse {a:.4f}, brake "
          f"{e:.4f} at x {x2:.3f}: {late:.3f} ({late / one:.2f} x)")
    assert late < one


@pytest.mark.parametrize(("inputs", "why"), [
    (dict(nOrder=1), "one lag: one switch lands it"),
    (dict(fLAway=1.0), "no brake at the other limit"),
    (dict(fRiseSecond=1.0), "no second point below W"),
    (dict(fAMax=0.1), "the first plan at the longest"),
], ids=lambda v: v if isinstance(v, str) else "")
def test_no_longer_pulse_where_no_second_plan_can_brake_it(fn: ScanDriver, inputs: dict, why: str) -> None:
    got = run(fn, **inputs)
    assert got.get("fPlan") == got.get("fFirst"), why
