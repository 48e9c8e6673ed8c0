"""FC_HeatUpTwoLagBrakePeak, FC_HeatUpLagBrakeFor and FC_HeatUpLagBrakePlan: the pulse-and-brake plan of
the model-based setpoint response on two unequal lags, against the same response evaluated densely in
double precision. The lags are a TCLab-like heater's (sensor 140 s behind a block 16.7 s behind the heater)
and a forming platform's (a bath about 30 times slower than the loop); the shares are a 45 -> 60 degC step
at 0.6 degC/% from 40 %, the heater's limits 0 and 100 %."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app, scan_with

TCLAB_RHO = 16.7 / 140.0
BATH_RHO = 0.033
L_TOWARD, L_AWAY = 60.0 / 25.0, -40.0 / 25.0  # (Ylim - Y0) / (Yh - Y0): 100 % and 0 % against 40 -> 65 %
PEAK_SHARE = 0.0025
A_MAX = 3.0

DECLS = """    fRatio, fA, fL, fE, fLAway, fPeak, fPostMin, fEMax, fEFor, fPostFor : REAL;
    fAFirst, fAPlan, fEPlan, fReach, fFirst : REAL;"""
BODY = f"""  fPeak := FC_HeatUpTwoLagBrakePeak(fRatio := fRatio, fA := fA, fL := fL, fE := fE,
                                    fLAway := fLAway, fPostMin => fPostMin);
  fEFor := FC_HeatUpLagBrakeFor(fRatio := fRatio, fA := fA, fLToward := fL, fLAway := fLAway, fEMax := fEMax,
                                fPostMin => fPostFor);
  fFirst := FC_HeatUpNLagPlan(nOrder := 2, fRatio := fRatio, fLToward := fL, fLAway := fLAway, fD := 0.0,
                              fB := 0.0, fXStart := 0.0, fAMax := {A_MAX});
  fAPlan := FC_HeatUpLagBrakePlan(fRatio := fRatio, fLToward := fL, fLAway := fLAway, fAFirst := fAFirst,
                                  fAMax := {A_MAX}, fMinBrake := 0.0001, fReach := fReach,
                                  fBrake => fEPlan);"""


def step(x: np.ndarray, rho: float) -> np.ndarray:
    """Unit step response of 1 / ((s + 1)(rho s + 1)) at x = t / T."""
    x = np.maximum(x, 0.0)
    return 1.0 - (np.exp(-x) - rho * np.exp(-x / rho)) / (1.0 - rho)


def response(x: np.ndarray, rho: float, a: float, e: float, lt: float = L_TOWARD,
             la: float = L_AWAY) -> np.ndarray:
    """The share lt for a lags, la for e lags, then 1: the response over the step, densely."""
    return lt * step(x, rho) + (la - lt) * step(x - a, rho) + (1.0 - la) * step(x - a - e, rho)


def dense_peak(rho: float, a: float, e: float) -> tuple[float, float]:
    x = np.linspace(0.0, a + e + 12.0, 400_001)
    m = response(x, rho, a, e)
    k = int(np.argmax(m))
    return float(m[k]), float(min(m[k:].min(), 1.0))


def band_entry(rho: float, a: float, e: float, band: float = 0.02) -> float:
    """When the response last enters the 2 % band, lags."""
    x = np.linspace(0.0, a + e + 12.0, 200_001)
    out = np.abs(response(x, rho, a, e) - 1.0) > band
    return float(x[np.flatnonzero(out)[-1] + 1])


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


def run(fn: ScanDriver, **inputs: float) -> ScanDriver:
    return scan_with(fn, dict(fRatio=TCLAB_RHO, fA=0.5, fL=L_TOWARD, fE=0.0, fLAway=L_AWAY, fEMax=0.5,
                              fAFirst=0.5, fReach=1.0), inputs)


@pytest.mark.parametrize(("rho", "a", "e"), [(TCLAB_RHO, 0.5, 0.0), (TCLAB_RHO, 0.6, 0.04),
                                             (TCLAB_RHO, 0.7, 0.2), (BATH_RHO, 0.3, 0.02),
                                             (BATH_RHO, 0.4, 0.3), (0.5, 0.8, 0.1)])
def test_the_peak_of_a_pulse_and_a_brake_is_exact(fn: ScanDriver, rho: float, a: float, e: float) -> None:
    """Turning points solved per interval, against a grid of 400,001 points."""
    peak, post = dense_peak(rho, a, e)
    got = run(fn, fRatio=rho, fA=a, fE=e)
    print(f"rho {rho:.3f}, a {a}, e {e}: peak {got.get('fPeak'):.6f} (dense {peak:.6f}), "
          f"after it down to {got.get('fPostMin'):.6f} ({post:.6f})")
    assert got.get("fPeak") == pytest.approx(peak, abs=2e-5)
    assert got.get("fPostMin") == pytest.approx(post, abs=2e-5)


def test_the_brake_is_the_shortest_that_keeps_the_peak_within_the_landing(fn: ScanDriver) -> None:
    a = 0.62
    got = run(fn, fA=a, fEMax=a)
    e = got.get("fEFor")
    assert e > 0.0
    assert dense_peak(TCLAB_RHO, a, e)[0] <= 1.0 + PEAK_SHARE + 1e-4
    assert dense_peak(TCLAB_RHO, a, 0.95 * e)[0] > 1.0 + PEAK_SHARE


def test_a_pulse_no_brake_can_land_has_none(fn: ScanDriver) -> None:
    assert run(fn, fA=2.0, fEMax=0.01).get("fEFor") == -1.0


@pytest.mark.parametrize(("rho", "gain"), [(TCLAB_RHO, 0.95), (BATH_RHO, 1.0)])
def test_the_plan_lands_within_the_tolerance_and_sooner_than_one_switch(fn: ScanDriver, rho: float,
                                                                          gain: float) -> None:
    """The closer the lags, the more the chain holds after one switch and the more a brake gains; lags far
    apart are nearly one lag, which one switch already lands at its best."""
    first = run(fn, fRatio=rho).get("fFirst")
    got = run(fn, fRatio=rho, fAFirst=first, fReach=0.8)
    a, e = got.get("fAPlan"), got.get("fEPlan")
    peak, post = dense_peak(rho, a, e)
    one, two = band_entry(rho, first, 0.0), band_entry(rho, a, e)
    print(f"rho {rho:.3f}: one switch at {first:.4f} lags enters the band at {one:.4f}; pulse {a:.4f} and "
          f"brake {e:.4f} at {two:.4f} ({two / one:.2f} x), peak {100 * (peak - 1):.3f} %, "
          f"back to {100 * (post - 1):.3f} %")
    assert a > first and e > 0.0
    assert peak <= 1.0 + PEAK_SHARE + 1e-4
    assert post >= 1.0 - PEAK_SHARE - 1e-4
    assert two <= gain * one


def test_the_plan_goes_its_share_of_the_way_to_the_longest_pulse(fn: ScanDriver) -> None:
    first = run(fn).get("fFirst")
    full = run(fn, fAFirst=first, fReach=1.0).get("fAPlan")
    half = run(fn, fAFirst=first, fReach=0.5).get("fAPlan")
    assert half == pytest.approx(first + 0.5 * (full - first), rel=1e-5)
    # one step past the edge, no brake lands the response within the tolerance both ways
    beyond = full + 0.02 * (full - first)
    e = run(fn, fA=beyond, fEMax=beyond).get("fEFor")
    assert e < 0.0 or run(fn, fA=beyond, fEMax=beyond).get("fPostFor") < 1.0 - PEAK_SHARE


@pytest.mark.parametrize(("l_away", "a_first"), [(1.0, 0.5), (L_AWAY, 0.0), (L_AWAY, A_MAX)],
                         ids=["no brake at the other limit", "no first plan", "first plan at the longest"])
def test_no_plan_where_a_brake_cannot_help(fn: ScanDriver, l_away: float, a_first: float) -> None:
    got = run(fn, fLAway=l_away, fAFirst=a_first)
    assert got.get("fAPlan") == 0.0
    assert got.get("fEPlan") == 0.0
    assert not math.isnan(got.get("fPeak"))
