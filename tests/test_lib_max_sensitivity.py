"""FC_CtrlMaxSensitivity: Ms of FB_CtrlPid's form on an FOPDT model, as the tuner publishes it (fMsTuned),
against the same loop evaluated in numpy on a fine frequency grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from modbus_bridge.plants.response import max_sensitivity, pid_frequency_response
from tests.st_helpers import ScanDriver, build_program, load_test_app

DECLS = """    fKs, fTu, fTg, fKp, fTn, fTv, fTd, fMs : REAL;"""
BODY = """  fMs := FC_CtrlMaxSensitivity(fKs := fKs, fTu := fTu, fTg := fTg, fKp := fKp, fTn := fTn,
                                fTv := fTv, fTd := fTd);"""
NAMES = ("fKs", "fTu", "fTg", "fKp", "fTn", "fTv", "fTd")


def reference(ks: float, l: float, t: float, kp: float, tn: float, tv: float, td: float) -> float:
    w = np.logspace(-6, 3, 200_000)
    plant = ks * np.exp(-1j * w * l) / (1j * w * t + 1.0)
    return max_sensitivity(pid_frequency_response(kp, tn, tv, td, w) * plant)


@pytest.fixture(scope="module")
def fn() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY)))


CASES = [
    (0.5916, 10.6, 23.4, 5.32, 22.2, 3.58, 0.895),  # seed 003, the self-tuned set
    (0.5916, 10.6, 23.4, 1.87, 23.4, 0.0, 0.0),     # seed 003, SIMC PI
    (3.4, 5.5, 140.0, 3.43, 47.6, 0.0, 0.0),        # T1 as written
    (2.2, 3.0, 45.0, 1.59, 68.5, 14.4, 3.6),        # a lag-dominated oven
    (1.0, 30.0, 20.0, 0.3, 25.0, 0.0, 0.0),         # delay-dominated
    (1.0, 0.0, 20.0, 2.0, 10.0, 0.0, 0.0),          # no dead time
]


@pytest.mark.parametrize("case", CASES)
def test_matches_the_loop_evaluated_in_numpy(fn: ScanDriver, case) -> None:
    ks, l, t, kp, tn, tv, td = case
    for name, value in zip(NAMES, case, strict=True):
        fn.set(name, value)
    fn.scan()
    assert fn.get("fMs") == pytest.approx(reference(ks, l, t, kp, tn, tv, td), rel=0.02)


@pytest.mark.parametrize("bad", [(0.0, 10.0, 20.0), (1.0, 10.0, 0.0), (1.0, -1.0, 20.0), (math.nan, 1, 2.0)])
def test_an_unusable_model_gives_zero(fn: ScanDriver, bad) -> None:
    for name, value in zip(NAMES, (*bad, 1.0, 10.0, 0.0, 0.0), strict=True):
        fn.set(name, value)
    fn.scan()
    assert fn.get("fMs") == 0.0


def test_an_unstable_loop_is_far_above_any_limit(fn: ScanDriver) -> None:
    for name, value in zip(NAMES, (1.0, 10.0, 20.0, 50.0, 5.0, 0, 0), strict=True):
        fn.set(name, value)
    fn.scan()
    assert fn.get("fMs") > 2.0 and math.isfinite(fn.get("fMs"))


FILTER_DECLS = """    fKs, fTu, fTg, fKp, fTn, fTv, fTd, fTFilter, fMs : REAL;"""
FILTER_BODY = """  fMs := FC_CtrlMaxSensitivity(fKs := fKs, fTu := fTu, fTg := fTg, fKp := fKp, fTn := fTn,
                                fTv := fTv, fTd := fTd, fTFilter := fTFilter);"""
SEED002_SIMC = (5.19, 1.05, 194.8, 17.87, 8.4, 0.0, 0.0)  # seed 002's hot end and its SIMC PI set


@pytest.fixture(scope="module")
def fn_filter() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(FILTER_DECLS, FILTER_BODY)))


@pytest.mark.parametrize("share", [0.0, 0.1, 0.5, 1.0])
def test_the_actual_value_filter_lag_counts_against_the_robustness(fn_filter: ScanDriver, share) -> None:
    """The loop is C F P with F = 1/(Tf s + 1): the PID acts on the filtered X."""
    ks, l, t, kp, tn, tv, td = SEED002_SIMC
    tf = share * l
    for name, value in zip((*NAMES, "fTFilter"), (*SEED002_SIMC, tf), strict=True):
        fn_filter.set(name, value)
    fn_filter.scan()
    w = np.logspace(-6, 3, 200_000)
    loop = pid_frequency_response(kp, tn, tv, td, w) * ks * np.exp(-1j * w * l) / (1j * w * t + 1.0)
    expected = max_sensitivity(loop / (1j * w * tf + 1.0))
    assert fn_filter.get("fMs") == pytest.approx(expected, rel=0.02)
    if share > 0.0:
        assert fn_filter.get("fMs") > reference(*SEED002_SIMC)
