"""Bad input: every parameter is checked in ST before use (docs/library.md, "Parameter check")."""

from __future__ import annotations

import math
import random

import pytest

from tests.st_helpers import ScanDriver, controller_program, load_test_app

ACTIVE = 2
PARAM_BIT = 0x10000


@pytest.fixture()
def uut() -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", 2.0), ("fTn", 50.0), ("fWatchPeriod", 0.0), ("fRunawayPeriod", 0.0)):
        drv.set(f"sPar.{name}", value)
    drv.set("fbUut.fW1", 50.0)
    drv.set("fbUut.fX", 40.0)
    drv.set("nMode", ACTIVE)
    drv.scan(3)
    drv.set("sPar.bAlarmLatch", False)
    drv.scan()
    return drv


@pytest.mark.parametrize(
    ("field", "bad"),
    [("fKp", math.nan), ("fKp", -1.0), ("fKp", math.inf), ("fTn", math.inf), ("fTv", -0.5), ("fTd", math.nan),
     ("fKpCool", -3.0), ("fPwmPeriod", 0.0), ("fTempAbsHigh", math.nan), ("fTuneStabilisation", -1.0)],
)
def test_invalid_field_keeps_last_valid_value(uut: ScanDriver, field: str, bad: float) -> None:
    good = uut.get(f"fbUut.sValid.{field}")
    uut.set(f"sPar.{field}", bad)
    uut.scan()
    assert uut.get(f"fbUut.sValid.{field}") == good
    assert uut.get("fbUut.dwAlarm") & PARAM_BIT
    assert uut.get("fbUut.bParamError") is True
    assert uut.get("fbUut.nErrorId") == 3
    y = uut.get("fbUut.fY")
    assert math.isfinite(y) and 0.0 <= y <= 100.0
    uut.set(f"sPar.{field}", good)
    uut.scan()
    assert not uut.get("fbUut.dwAlarm") & PARAM_BIT
    assert uut.get("fbUut.nErrorId") == 0


def test_tn_not_positive_is_valid_integral_off(uut: ScanDriver) -> None:
    uut.set("sPar.fTn", 0.0)
    uut.scan()
    assert not uut.get("fbUut.dwAlarm") & PARAM_BIT
    i0 = uut.get("fbUut.fI")
    uut.scan(10)
    assert uut.get("fbUut.fI") == pytest.approx(i0)


@pytest.mark.parametrize(("ymin", "ymax"), [(50.0, 10.0), (-150.0, 100.0), (0.0, 120.0), (math.nan, 100.0)])
def test_output_limits_checked_as_a_pair(uut: ScanDriver, ymin: float, ymax: float) -> None:
    uut.set("sPar.fYMin", ymin)
    uut.set("sPar.fYMax", ymax)
    uut.scan()
    assert uut.get("fbUut.sValid.fYMin") == 0.0 and uut.get("fbUut.sValid.fYMax") == 100.0
    assert uut.get("fbUut.dwAlarm") & PARAM_BIT


def test_cycle_time_errors(uut: ScanDriver) -> None:
    uut.set("sPar.fTaskCycleTime", math.nan)
    uut.scan()
    assert uut.get("fbUut.nErrorId") == 1
    uut.set("sPar.fTaskCycleTime", 0.1)
    uut.set("sPar.fCtrlCycleTime", 0.05)  # below the task cycle
    uut.scan()
    assert uut.get("fbUut.nErrorId") == 2
    assert uut.get("fbUut.sValid.fCtrlCycleTime") == pytest.approx(0.1)


@pytest.mark.parametrize("w", [1000.0, -50.0, math.nan, math.inf])
def test_setpoint_outside_range_keeps_last(uut: ScanDriver, w: float) -> None:
    uut.set("fbUut.fW1", w)
    uut.scan()
    assert uut.get("fbUut.fW") == 50.0
    assert uut.get("fbUut.dwAlarm") & PARAM_BIT


def test_unknown_mode_code_keeps_mode(uut: ScanDriver) -> None:
    uut.set("nMode", 42)
    uut.scan()
    assert uut.get("nModeRejected") is True
    assert uut.get("nState") == ACTIVE


def test_manual_value_nan_keeps_last(uut: ScanDriver) -> None:
    uut.set("fbUut.fYManual", 20.0)
    uut.set("nMode", 4)
    uut.scan()
    uut.set("fbUut.fYManual", math.nan)
    uut.scan()
    assert uut.get("fbUut.fY") == 20.0
    assert uut.get("fbUut.bParamError") is True


def test_random_garbage_never_gives_nan_or_out_of_limits(uut: ScanDriver) -> None:
    rng = random.Random(11)
    fields = ["fKp", "fTn", "fTv", "fTd", "fYMin", "fYMax", "fCtrlCycleTime", "fTaskCycleTime", "fWVeloPos",
              "fTFilter", "fKpCool", "fTnCool", "fYOnFailure", "fWMin", "fWMax"]
    garbage = [math.nan, math.inf, -math.inf, 1e30, -1e30, -1.0, 0.0, 3e38]
    for _ in range(400):
        for f in rng.sample(fields, 3):
            uut.set(f"sPar.{f}", rng.choice(garbage + [rng.uniform(-200, 200)]))
        uut.set("fbUut.fX", rng.choice([rng.uniform(-100, 600), math.nan]))
        uut.set("fbUut.fW1", rng.choice([rng.uniform(-100, 600), math.nan]))
        uut.set("nMode", rng.choice([1, 2, 2, 2, 4, 5, 9]))
        uut.set("fbUut.fYManual", rng.choice([rng.uniform(-200, 200), math.nan]))
        uut.scan()
        y = uut.get("fbUut.fY")
        lo, hi = uut.get("fbUut.sValid.fYMin"), uut.get("fbUut.sValid.fYMax")
        assert math.isfinite(y) and lo <= y <= hi
        assert -100.0 <= lo < hi <= 100.0
