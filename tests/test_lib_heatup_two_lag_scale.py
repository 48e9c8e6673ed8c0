"""FC_HeatUpTwoLagScale and FC_HeatUpTwoLagFit: the lags a plant of two unequal lags shows, from the line
through its rise under the limit step, against the same plant's response evaluated in double precision; and
FC_LagModelWindowLine, the model's line over a window, against numpy's least-squares line. The lags are the
TCLab-like heater's (sensor 140 s behind a block 16.7 s behind the heater)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app, scan_with

SLOW_S, FAST_S, DELAY_S = 140.0, 16.7, 0.0
RHO = FAST_S / SLOW_S
SCALE_RANGE = 2.0
NEEDED_SHARE = 0.25  # the step needs this share of the limit step's end value
WINDOW = (0.2, 0.4)  # the rise's two crossings, shares of the step

DECLS = """    fSlope, fMean, fT, fHalf, fFastIn, fScale, fSlow, fFast, fX, fLineSlope, fLineMean : REAL;
    bFit : BOOL;"""
BODY = f"""  fScale := FC_HeatUpTwoLagScale(fSlope := fSlope, fT := fT, fHalf := fHalf, fDelay := {DELAY_S},
                                 fLag := {SLOW_S}, fRatio := {RHO}, fFastScale := fFastIn,
                                 fScaleRange := {SCALE_RANGE});
  bFit := FC_HeatUpTwoLagFit(fSlope := fSlope, fMean := fMean, fT := fT, fHalf := fHalf, fDelay := {DELAY_S},
                             fLag := {SLOW_S}, fRatio := {RHO}, fScaleRange := {SCALE_RANGE},
                             fSlowScale => fSlow, fFastScale => fFast);
  fLineSlope := FC_LagModelWindowLine(fX := fX, fHalf := fHalf, nOrder := 2, fRatio := {RHO},
                                      fMean => fLineMean);"""


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


def run(fn: ScanDriver, **inputs: float) -> ScanDriver:
    return scan_with(fn, dict(fSlope=0.0, fMean=0.0, fT=0.0, fHalf=0.0, fFastIn=1.0, fX=0.0), inputs)


def scale(fn: ScanDriver, slope: float, t: float) -> float:
    return run(fn, fSlope=slope, fT=t).get("fScale")


def window_line(slow: float, fast: float, gain: float = 1.0) -> dict[str, float]:
    """The least-squares line through the rise (over K dY) between the two crossings of a step that needs
    NEEDED_SHARE of the limit step's end value, sampled every 0.1 s: what the setpoint response hands over."""
    t = np.arange(0.0, 300.0, 0.1)
    r = gain * np.array([unit_rise(v, slow * SLOW_S, fast * FAST_S) for v in t])
    window = (r >= WINDOW[0] * NEEDED_SHARE) & (r <= WINDOW[1] * NEEDED_SHARE)
    slope, _ = np.polyfit(t[window], r[window], 1)
    return dict(fSlope=float(slope), fMean=float(r[window].mean()), fT=float(t[window].mean()),
                fHalf=math.sqrt(3.0 * float(t[window].var())))


@pytest.mark.parametrize("s", [0.6, 0.7, 0.9, 1.0, 1.3, 1.8])
def test_the_slow_lag_is_found_from_the_exact_slope(fn: ScanDriver, s: float) -> None:
    assert scale(fn, unit_slope(40.0, s * SLOW_S, FAST_S), 40.0) == pytest.approx(s, rel=1e-3)


def test_the_line_through_the_rise_tells_the_slow_lag(fn: ScanDriver) -> None:
    """The window's line against the model's line over the same window, the fast lag the model's."""
    for s in (0.7, 1.0, 1.3):
        line = window_line(s, 1.0)
        got = run(fn, fSlope=line["fSlope"], fT=line["fT"], fHalf=line["fHalf"]).get("fScale")
        print(f"slow lag x {s}: seen x {got:.4f}")
        assert got == pytest.approx(s, rel=2e-3)


@pytest.mark.parametrize(("slow", "fast"), [(1.0, 1.0), (1.3, 1.0), (0.7, 1.0), (1.0, 1.3), (1.0, 0.7),
                                            (1.2, 0.8)])
def test_the_line_s_slope_and_level_tell_both_lags(fn: ScanDriver, slow: float, fast: float) -> None:
    line = window_line(slow, fast)
    got = run(fn, **line)
    print(f"slow x {slow}, fast x {fast}: seen slow x {got.get('fSlow'):.4f}, fast x {got.get('fFast'):.4f}")
    assert got.get("bFit")
    assert got.get("fSlow") == pytest.approx(slow, rel=5e-3)
    assert got.get("fFast") == pytest.approx(fast, rel=5e-3)


def test_a_slower_block_is_not_read_as_a_slower_sensor(fn: ScanDriver) -> None:
    """The fast lag still settles in the window: its slope alone reads a block 30 % slower as a slow lag
    several % longer; with the line's level the slow lag is the model's."""
    line = window_line(1.0, 1.3)
    by_slope = run(fn, fSlope=line["fSlope"], fT=line["fT"], fHalf=line["fHalf"]).get("fScale")
    fitted = run(fn, **line).get("fSlow")
    print(f"block x 1.3: slow lag by the slope alone x {by_slope:.3f}, with the level x {fitted:.3f}")
    assert by_slope > 1.04
    assert fitted == pytest.approx(1.0, rel=5e-3)


@pytest.mark.parametrize("s", [0.7, 1.0, 1.3])
def test_a_level_no_fast_lag_in_range_gives_reads_both_lags_scaled_alike(fn: ScanDriver, s: float) -> None:
    """A plant whose lags are both s times the model's, its level past every fast lag at the slope's s (a
    model whose dead time and fast lag are split unlike the plant's): the slope read with the fast lag
    scaled alike, not the model's, which would put the fast lag's share of the rise on the slow lag."""
    line = window_line(s, s) | dict(fMean=0.001)
    with_model_fast = run(fn, fSlope=line["fSlope"], fT=line["fT"], fHalf=line["fHalf"]).get("fScale")
    got = run(fn, **line)
    print(f"both lags x {s}: slope with the model's fast lag x {with_model_fast:.4f}, "
          f"alike x {got.get('fSlow'):.4f}")
    assert got.get("bFit")
    assert got.get("fSlow") == pytest.approx(s, rel=2e-3)
    assert got.get("fFast") == got.get("fSlow")
    if s != 1.0:
        assert abs(with_model_fast - s) > 10 * abs(got.get("fSlow") - s)


@pytest.mark.parametrize(("x", "half"), [(0.25, 0.06), (0.1, 0.05), (0.5, 0.2), (0.3, 0.0)])
def test_the_model_s_window_line_is_the_least_squares_line(fn: ScanDriver, x: float, half: float) -> None:
    xs = np.linspace(x - half, x + half, 2001)
    g = np.array([unit_rise(v * SLOW_S, SLOW_S, FAST_S) for v in xs])
    got = run(fn, fX=x, fHalf=half)
    if half == 0.0:
        exact = SLOW_S * unit_slope(x * SLOW_S, SLOW_S, FAST_S)
        assert got.get("fLineSlope") == pytest.approx(exact, rel=1e-4)
        assert got.get("fLineMean") == pytest.approx(unit_rise(x * SLOW_S, SLOW_S, FAST_S), rel=1e-4)
        return
    slope, _ = np.polyfit(xs, g, 1)
    assert got.get("fLineSlope") == pytest.approx(slope, rel=1e-3)
    assert got.get("fLineMean") == pytest.approx(g.mean(), rel=1e-3)


@pytest.mark.parametrize(("slope", "t"), [(0.0, 40.0), (-1e-3, 40.0), (1.0, 40.0), (1e-9, 40.0),
                                          (unit_slope(40.0, SLOW_S, FAST_S), DELAY_S)],
                         ids=["flat", "falling", "steeper than any lag in range", "flatter than any",
                              "before the dead time"])
def test_a_slope_no_lag_in_range_gives_is_no_scale(fn: ScanDriver, slope: float, t: float) -> None:
    assert scale(fn, slope, t) == 0.0
    assert not run(fn, fSlope=slope, fT=t, fMean=0.1).get("bFit")
