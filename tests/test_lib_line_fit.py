"""FB_LineFit, the running least-squares line the tuner (the rest's drift) and the setpoint response (the
dead time from the early rise, the lags from the rise's window) read: against numpy's polyfit and variance
on the same points, after a reset, and with too few distinct x for a slope."""

from __future__ import annotations

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, f32, load_test_app

DECLS = """    fbLine : FB_LineFit;
    bReset : BOOL;
    bAdd : BOOL;
    fX : REAL;
    fY : REAL;"""
BODY = """  IF bReset THEN
    fbLine(bReset := TRUE);
  ELSIF bAdd THEN
    fbLine(bReset := FALSE, fX := fX, fY := fY);
  END_IF;"""
TOLERANCE = 1e-4  # relative, REAL against double


@pytest.fixture(scope="module")
def drv() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


def feed(drv: ScanDriver, xs, ys) -> None:
    drv.set("bAdd", False)
    drv.set("bReset", True)
    drv.scan()
    drv.set("bReset", False)
    drv.set("bAdd", True)
    for x, y in zip(xs, ys, strict=True):
        drv.set("fX", x)
        drv.set("fY", y)
        drv.scan()
    drv.set("bAdd", False)


def test_the_line_is_numpy_s_least_squares_line(drv: ScanDriver) -> None:
    rng = np.random.default_rng(5)
    xs = 30.0 + 0.1 * np.arange(200)  # a late window of a record: large x, small spread
    ys = 4.0 - 0.8 * (xs - 30.0) + rng.normal(0.0, 0.2, xs.size)
    xs32 = np.array([f32(v) for v in xs])
    ys32 = np.array([f32(v) for v in ys])
    feed(drv, xs32, ys32)
    slope, intercept = np.polyfit(xs32, ys32, 1)
    assert drv.get("fbLine.nCount") == xs.size
    assert drv.get("fbLine.bValid")
    assert drv.get("fbLine.fSlope") == pytest.approx(slope, rel=TOLERANCE)
    assert drv.get("fbLine.fMeanX") == pytest.approx(xs32.mean(), rel=TOLERANCE)
    assert drv.get("fbLine.fMeanY") == pytest.approx(ys32.mean(), rel=TOLERANCE)
    assert drv.get("fbLine.fVarX") == pytest.approx(xs32.var(), rel=1e-3)
    assert drv.get("fbLine.fMeanY") - drv.get("fbLine.fSlope") * drv.get("fbLine.fMeanX") == pytest.approx(
        intercept, rel=TOLERANCE)


def test_a_reset_starts_a_new_line(drv: ScanDriver) -> None:
    feed(drv, [0.0, 1.0, 2.0], [5.0, 3.0, 1.0])
    feed(drv, [10.0, 11.0], [1.0, 4.0])
    assert drv.get("fbLine.nCount") == 2
    assert drv.get("fbLine.fSlope") == pytest.approx(3.0)


@pytest.mark.parametrize("xs", [[1.0], [2.0, 2.0, 2.0]], ids=["one point", "one x"])
def test_without_two_distinct_x_there_is_no_slope(drv: ScanDriver, xs: list[float]) -> None:
    feed(drv, xs, [1.0 + i for i in range(len(xs))])
    assert not drv.get("fbLine.bValid")


def test_the_slope_variance_is_the_ordinary_least_squares_one(drv: ScanDriver) -> None:
    """(residual sum of squares / (n - 2)) / Sxx: the standard error the setpoint response weighs a seen
    lag against."""
    rng = np.random.default_rng(11)
    xs = np.array([f32(v) for v in 40.0 + 0.1 * np.arange(150)])
    ys = np.array([f32(v) for v in 3.0 + 0.25 * (xs - 40.0) + rng.normal(0.0, 0.2, xs.size)])
    feed(drv, xs, ys)
    slope, intercept = np.polyfit(xs, ys, 1)
    residual = ys - (slope * xs + intercept)
    expected = float(residual @ residual) / (xs.size - 2) / float(((xs - xs.mean()) ** 2).sum())
    assert drv.get("fbLine.fSlopeVar") == pytest.approx(expected, rel=1e-3)


def test_points_on_a_line_leave_no_slope_variance(drv: ScanDriver) -> None:
    feed(drv, [0.0, 1.0, 2.0, 3.0], [1.0, 3.0, 5.0, 7.0])
    assert drv.get("fbLine.fSlopeVar") == pytest.approx(0.0, abs=1e-9)
