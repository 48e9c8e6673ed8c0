"""FC_HeatUpNLagFit: the lags and gain of a chain of equal lags from two points of its rise after the
model-based setpoint response's pulse, against the same chain's response evaluated with scipy."""

from __future__ import annotations

import pytest
from scipy.optimize import brentq
from scipy.special import gammainc

from tests.st_helpers import ScanDriver, build_program, load_test_app

# the bench oven's plan from rest (test_lib_heatup: 100 -> 150 degC on 2.2 e^(-4 s) / (45 s + 1)^4)
ORDER, LAG_S, DELAY_S, PULSE_S, LIMIT_SHARE = 4, 45.0, 4.0, 18.15, 4.402
R1, R2 = 0.2, 0.4  # the two points, shares of the step
SCALE_KEEP, GAIN_KEEP = 1.05, 0.1

DECLS = """    fT1, fR1, fT2, fR2, fScale, fGain : REAL;
    bFits : BOOL;"""
BODY = f"""  bFits := FC_HeatUpNLagFit(nOrder := {ORDER}, fT1 := fT1, fR1 := fR1, fT2 := fT2, fR2 := fR2,
                            fDelay := {DELAY_S}, fLag := {LAG_S}, fTOn := {PULSE_S}, fL := {LIMIT_SHARE},
                            fScale => fScale, fGain => fGain);"""


def rise(t: float, order: int, lag_s: float, gain: float) -> float:
    """The share of the step a chain of `order` lags of `lag_s` (gain times the model's) has risen by at t
    on the plan's pulse and then its holding power."""
    def unit(x: float) -> float:
        return float(gammainc(order, max(x, 0.0)))
    x = (t - DELAY_S) / lag_s
    return gain * (LIMIT_SHARE * unit(x) + (1.0 - LIMIT_SHARE) * unit(x - PULSE_S / lag_s))


def points(order: int, lag_s: float, gain: float) -> tuple[float, float]:
    return tuple(brentq(lambda t, r=r: rise(t, order, lag_s, gain) - r, DELAY_S, 20.0 * lag_s * order)
                 for r in (R1, R2))


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


def fit(fn: ScanDriver, t1: float, t2: float) -> tuple[bool, float, float]:
    for name, value in dict(fT1=t1, fR1=R1, fT2=t2, fR2=R2).items():
        fn.set(name, value)
    fn.scan()
    return fn.get("bFits"), fn.get("fScale"), fn.get("fGain")


@pytest.mark.parametrize(("scale", "gain"), [(0.7, 1.0), (1.3, 1.0), (1.0, 0.8), (1.0, 1.2), (0.8, 1.25),
                                             (1.2, 0.85)])
def test_lags_and_gain_off_the_model_are_told_apart(fn: ScanDriver, scale: float, gain: float) -> None:
    """Shorter lags and a higher gain both reach the first point early; the time to the second differs."""
    fits, s, g = fit(fn, *points(ORDER, LAG_S * scale, gain))
    assert fits
    assert s == pytest.approx(scale, rel=0.01)
    assert g == pytest.approx(gain, rel=0.01)


def test_a_plant_close_to_its_model_is_the_model(fn: ScanDriver) -> None:
    fits, s, g = fit(fn, *points(ORDER, LAG_S * 1.03, 1.06))
    assert fits
    assert (s, g) == (1.0, 1.0)


def test_a_gain_close_to_the_model_s_leaves_the_lags_from_the_second_point(fn: ScanDriver) -> None:
    scale = 1.2
    fits, s, g = fit(fn, *points(ORDER, LAG_S * scale, 1.0 + 0.5 * GAIN_KEEP))
    assert fits and g == 1.0
    assert s == pytest.approx(scale, rel=0.05)


@pytest.mark.parametrize(("order", "lag_s"), [(1, ORDER * LAG_S), (2, 0.5 * ORDER * LAG_S)])
def test_a_rise_without_the_model_s_shape_is_not_fitted(fn: ScanDriver, order: int, lag_s: float) -> None:
    """A chain of fewer lags than the model's starts its rise too early for any lags and gain near it."""
    fits, s, g = fit(fn, *points(order, lag_s, 1.0))
    assert not fits
    assert (s, g) == (1.0, 1.0)
