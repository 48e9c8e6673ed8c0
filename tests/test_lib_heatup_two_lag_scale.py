"""FC_HeatUpTwoLagScale: the slow lag a plant of two unequal lags shows, from the slope of its rise under
the limit step, against the same plant's response evaluated in double precision. The lags are the
TCLab-like heater's (sensor 140 s behind a block 16.7 s behind the heater); the slope is the exact one at the
given time, and a line through the rise (what the setpoint response hands over) is checked too."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app

SLOW_S, FAST_S, DELAY_S = 140.0, 16.7, 0.0
RHO = FAST_S / SLOW_S
SCALE_RANGE = 2.0

DECLS = """    fSlope, fT, fScale : REAL;"""
BODY = f"""  fScale := FC_HeatUpTwoLagScale(fSlope := fSlope, fT := fT, fDelay := {DELAY_S}, fLag := {SLOW_S},
                                 fRatio := {RHO}, fScaleRange := {SCALE_RANGE});"""


def unit_slope(t: float, slow_s: float, fast_s: float) -> float:
    """d/dt of the unit step response of 1 / ((slow s + 1)(fast s + 1)), 1/s."""
    t = max(t - DELAY_S, 0.0)
    return (math.exp(-t / slow_s) - math.exp(-t / fast_s)) / (slow_s - fast_s)


def unit_rise(t: float, slow_s: float, fast_s: float) -> float:
    t = max(t - DELAY_S, 0.0)
    return 1.0 - (slow_s * math.exp(-t / slow_s) - fast_s * math.exp(-t / fast_s)) / (slow_s - fast_s)


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


def scale(fn: ScanDriver, slope: float, t: float) -> float:
    fn.set("fSlope", slope)
    fn.set("fT", t)
    fn.scan()
    return fn.get("fScale")


@pytest.mark.parametrize("s", [0.6, 0.7, 0.9, 1.0, 1.3, 1.8])
def test_the_slow_lag_is_found_from_the_exact_slope(fn: ScanDriver, s: float) -> None:
    assert scale(fn, unit_slope(40.0, s * SLOW_S, FAST_S), 40.0) == pytest.approx(s, rel=1e-3)


def test_the_line_through_the_rise_tells_the_slow_lag(fn: ScanDriver) -> None:
    """A least-squares line through the rise between 20 % and 40 % of a step that needs 25 % of the limit
    step's end value: its slope at its mean time."""
    for s in (0.7, 1.0, 1.3):
        t = np.arange(0.0, 200.0, 0.1)
        r = np.array([unit_rise(v, s * SLOW_S, FAST_S) for v in t]) / 0.25
        window = (r >= 0.2) & (r <= 0.4)
        slope = np.polyfit(t[window], r[window], 1)[0] * 0.25
        got = scale(fn, float(slope), float(t[window].mean()))
        print(f"slow lag x {s}: seen x {got:.4f}")
        assert got == pytest.approx(s, rel=0.01)


@pytest.mark.parametrize(("slope", "t"), [(0.0, 40.0), (-1e-3, 40.0), (1.0, 40.0), (1e-9, 40.0),
                                          (unit_slope(40.0, SLOW_S, FAST_S), DELAY_S)],
                         ids=["flat", "falling", "steeper than any lag in range", "flatter than any",
                              "before the dead time"])
def test_a_slope_no_lag_in_range_gives_is_no_scale(fn: ScanDriver, slope: float, t: float) -> None:
    assert scale(fn, slope, t) == 0.0
