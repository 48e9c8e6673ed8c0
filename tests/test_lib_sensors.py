"""Sensor functions: PT100 Callendar-Van Dusen (seed 000 coefficients), NTC beta / Steinhart-Hart, scaling."""

from __future__ import annotations

import math

import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app

A, B, C = 3.90802e-3, -5.80195e-7, -4.2735e-12


def cvd(t: float, r0: float = 100.0) -> float:
    if t >= 0:
        return r0 * (1 + A * t + B * t * t)
    return r0 * (1 + A * t + B * t * t + C * (t - 100) * t**3)


def beta_temp(r: float, r25: float = 100e3, beta: float = 3950.0) -> float:
    return 1 / (1 / 298.15 + math.log(r / r25) / beta) - 273.15


DECLS = """    fTempIn : REAL;
    fResIn : REAL;
    fRes : REAL;
    fTemp : REAL;
    fNtcBeta : REAL;
    fNtcSh : REAL;
    fShA : REAL;
    fShB : REAL;
    fShC : REAL;
    nRaw : INT;
    fScaled : REAL;
    fDivider : REAL;"""
BODY = """  fRes := FC_TempToPt100(fTemp := fTempIn, fR0 := 100.0);
  fTemp := FC_Pt100ToTemp(fResistance := fResIn, fR0 := 100.0);
  fNtcBeta := FC_NtcBetaToTemp(fResistance := fResIn, fR25 := 100000.0, fBeta := 3950.0);
  fNtcSh := FC_NtcSteinhartHart(fResistance := fResIn, fA := fShA, fB := fShB, fC := fShC);
  fScaled := FC_ScaleRaw(nRaw := nRaw, nRawLow := 0, nRawHigh := 32767, fLow := 18.52, fHigh := 390.48);
  fDivider := FC_NtcDividerResistance(nRaw := nRaw, nRawFull := 32767, fRPullup := 4700.0,
                                      fROpen := 1.0E9);"""


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


@pytest.mark.parametrize("temp", [0.0, 100.0, -100.0, 850.0, -200.0, 25.0, 450.0])
def test_pt100_forward_and_inverse_against_cvd(fn: ScanDriver, temp: float) -> None:
    fn.set("fTempIn", temp)
    fn.set("fResIn", cvd(temp))
    fn.scan()
    assert fn.get("fRes") == pytest.approx(cvd(temp), rel=2e-6)
    assert fn.get("fTemp") == pytest.approx(temp, abs=0.01)


def test_pt100_reference_points() -> None:
    # the reference computation itself, against the values the seed's coefficients give by hand
    assert cvd(0.0) == pytest.approx(100.0)
    assert cvd(100.0) == pytest.approx(100 * (1 + 0.390802 - 0.00580195))
    assert cvd(-100.0) == pytest.approx(100 * (1 - 0.390802 - 0.00580195 - 4.2735e-12 * (-200) * (-1e6)))


@pytest.mark.parametrize("temp", [25.0, 100.0, 200.0, 260.0])
def test_ntc_beta_and_steinhart_hart(fn: ScanDriver, temp: float) -> None:
    def r_of(t: float) -> float:
        return 100e3 * math.exp(3950.0 * (1 / (t + 273.15) - 1 / 298.15))

    # Steinhart-Hart coefficients fitted through three points of the beta curve
    pts = [(25.0, r_of(25.0)), (150.0, r_of(150.0)), (280.0, r_of(280.0))]
    import numpy as np

    m = np.array([[1, math.log(r), math.log(r) ** 3] for _, r in pts])
    y = np.array([1 / (t + 273.15) for t, _ in pts])
    a, b, c = np.linalg.solve(m, y)
    fn.set("fShA", float(a))
    fn.set("fShB", float(b))
    fn.set("fShC", float(c))
    fn.set("fResIn", r_of(temp))
    fn.scan()
    assert fn.get("fNtcBeta") == pytest.approx(beta_temp(r_of(temp)), abs=0.02)
    assert fn.get("fNtcBeta") == pytest.approx(temp, abs=0.02)
    assert fn.get("fNtcSh") == pytest.approx(temp, abs=0.5)  # REAL precision of the ln^3 term


def test_raw_scaling_and_divider(fn: ScanDriver) -> None:
    fn.set("nRaw", 16384)
    fn.scan()
    assert fn.get("fScaled") == pytest.approx(18.52 + 16384 / 32767 * (390.48 - 18.52), rel=1e-6)
    ratio = 16384 / 32767
    assert fn.get("fDivider") == pytest.approx(4700.0 * ratio / (1 - ratio), rel=1e-5)
    fn.set("nRaw", 32767)
    fn.scan()
    assert fn.get("fDivider") == pytest.approx(1.0e9)
