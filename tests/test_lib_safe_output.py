"""Safe output: IDLE/PASSIVE/RESET and ERROR with reaction OFF give exactly 0 and both PWM outputs off in
the same scan whatever the limits; FAILVALUE/HOLD clamped; the integrator stays finite on any input."""

from __future__ import annotations

import math

import pytest

from tests.st_helpers import ScanDriver, controller_program, load_test_app

IDLE, PASSIVE, ACTIVE, RESET, MANUAL = 0, 1, 2, 3, 4
REACTION_FAILVALUE, REACTION_HOLD = 2, 3
SENSOR_OPEN, SENSOR_SHORT = 0x1, 0x40


@pytest.fixture()
def uut() -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", 5.0), ("fTn", 20.0), ("fWatchPeriod", 0.0), ("fRunawayPeriod", 0.0)):
        drv.set(f"sPar.{name}", value)
    drv.set("fbUut.fW1", 100.0)
    return drv


def scan(drv: ScanDriver, mode: int, x: float, n: int = 1) -> float:
    drv.set("nMode", mode)
    drv.set("fbUut.fX", x)
    drv.scan(n)
    return drv.get("fbUut.fY")


def outputs_off(drv: ScanDriver) -> bool:
    return drv.get("fbUut.fY") == 0.0 and not drv.get("fbUut.bYPWMPos") and not drv.get("fbUut.bYPWMNeg")


@pytest.mark.parametrize("limits", [(20.0, 80.0), (-80.0, -20.0), (-100.0, 100.0)])
@pytest.mark.parametrize("mode", [IDLE, PASSIVE, RESET, 6, 7])
def test_safe_modes_give_exact_zero_whatever_the_limits(uut, limits, mode):
    uut.set("sPar.fYMin", limits[0])
    uut.set("sPar.fYMax", limits[1])
    uut.set("sPar.fPwmPeriod", 10.0)
    scan(uut, ACTIVE, 95.0 if limits[1] > 0 else 105.0, n=20)
    assert uut.get("fbUut.fY") != 0.0
    assert uut.get("fbUut.bYPWMPos") or uut.get("fbUut.bYPWMNeg"), "a pulse runs before the mode change"
    scan(uut, mode, 95.0)
    assert outputs_off(uut), f"mode {mode}, limits {limits}: y={uut.get('fbUut.fY')}"
    scan(uut, mode, 95.0, n=30)
    assert outputs_off(uut)


@pytest.mark.parametrize("period", [1.0, 60.0])
def test_fault_ends_the_running_pwm_pulse_in_the_same_scan(uut, period):
    uut.set("sPar.fYMin", 10.0)
    uut.set("sPar.fPwmPeriod", period)
    scan(uut, ACTIVE, 90.0, n=2)
    assert uut.get("fbUut.bYPWMPos"), "the heater pulse is on"
    scan(uut, ACTIVE, math.nan)
    assert uut.get("fbUut.dwAlarm") & SENSOR_OPEN
    assert outputs_off(uut), "reaction OFF: output 0 and pulse ended in the scan the alarm appeared"


def test_failvalue_and_hold_are_clamped(uut):
    uut.set("sPar.fYMin", 10.0)
    uut.set("sPar.fYMax", 60.0)
    uut.set("sPar.fYOnFailure", 90.0)
    uut.set("sPar.eReactionOnFailure", REACTION_FAILVALUE)
    scan(uut, ACTIVE, 95.0, n=5)
    assert scan(uut, ACTIVE, math.nan) == 60.0
    uut.set("sPar.fYOnFailure", -50.0)
    assert scan(uut, ACTIVE, math.nan) == 10.0
    uut.set("sPar.eReactionOnFailure", REACTION_HOLD)
    assert 10.0 <= scan(uut, ACTIVE, math.nan) <= 60.0


def test_huge_finite_pv_at_manual_to_active_does_not_freeze_the_output(uut):
    uut.set("sPar.bAlarmLatch", False)
    uut.set("fbUut.fYManual", 50.0)
    scan(uut, MANUAL, 95.0, n=5)
    for x in (-1.0e38, 1.0e38, -3.0e38):
        scan(uut, ACTIVE, x, n=5)
        assert outputs_off(uut), "implausible PV: sensor alarm, reaction OFF"
        for name in ("fI", "fP", "fD"):
            assert math.isfinite(uut.get(f"fbUut.{name}")), name
    ys = [scan(uut, ACTIVE, 95.0) for _ in range(20)]
    assert all(math.isfinite(y) for y in ys)
    assert ys[-1] > ys[0], f"the PID integrates again once X is back: {ys[0]} -> {ys[-1]}"
    assert math.isfinite(uut.get("fbUut.fI"))


@pytest.mark.parametrize("x", [1.0e38, -1.0e38, 3.0e38])
def test_integrator_stays_finite_with_plausibility_limits_wide_open(uut, x):
    uut.set("sPar.fXMin", -1.0e9)
    uut.set("sPar.fXMax", 1.0e9)
    uut.set("sPar.fKp", 1.0e9)
    uut.set("sPar.fTn", 1.0e-3)
    uut.set("sPar.eReactionOnFailure", 0)
    scan(uut, ACTIVE, 95.0, n=3)
    scan(uut, ACTIVE, x, n=10)
    for name in ("fI", "fP", "fD", "fY"):
        assert math.isfinite(uut.get(f"fbUut.{name}")), name
    y = scan(uut, ACTIVE, 99.0, n=10)
    assert 0.0 <= y <= 100.0


def test_pid_kernel_refuses_non_finite_inputs() -> None:
    from tests.st_helpers import build_program

    drv = ScanDriver(load_test_app(build_program("    fbPid : FB_CtrlPid;", "  fbPid();")))
    for name, value in (("fW", 50.0), ("fX", 40.0), ("fKp", 2.0), ("fTn", 10.0), ("fYMin", 0.0),
                        ("fYMax", 100.0), ("fCycleTime", 0.1)):
        drv.set(f"fbPid.{name}", value)
    drv.scan(10)
    i_before, y_before = drv.get("fbPid.fI"), drv.get("fbPid.fY")
    for name, bad in (("fX", math.inf), ("fW", math.nan), ("fKp", math.inf), ("fTn", math.nan),
                      ("fCycleTime", 0.0), ("fSyncValue", math.nan)):
        good = drv.get(f"fbPid.{name}")
        drv.set(f"fbPid.{name}", bad)
        drv.scan()
        assert drv.get("fbPid.bInputError"), name
        assert drv.get("fbPid.fI") == i_before and drv.get("fbPid.fY") == y_before, name
        drv.set(f"fbPid.{name}", good)
    drv.scan()
    assert not drv.get("fbPid.bInputError")


def test_cycle_ratio_that_overflows_the_divider_is_refused(uut):
    for ctrl in (32767.5, 40000.0, 1.0e6):
        uut.set("sPar.fCtrlCycleTime", ctrl)
        scan(uut, ACTIVE, 95.0)
        assert uut.get("fbUut.bParamError"), ctrl
        assert uut.get("fbUut.sValid.fCtrlCycleTime") == pytest.approx(0.1)
    uut.set("sPar.fCtrlCycleTime", 0.1)
    uut.set("sPar.fTaskCycleTime", 1.0e-6)
    scan(uut, ACTIVE, 95.0)
    assert uut.get("fbUut.sValid.fTaskCycleTime") == pytest.approx(0.1), "ratio 1e5"
    uut.set("sPar.fTaskCycleTime", 0.1)
    uut.set("sPar.fPwmPeriod", 1.0e6)
    scan(uut, ACTIVE, 95.0)
    assert uut.get("fbUut.sValid.fPwmPeriod") == pytest.approx(1.0)


@pytest.mark.parametrize(("ntc", "x", "bit"), [(True, -100.0, SENSOR_OPEN), (True, 500.0, SENSOR_SHORT),
                                               (False, -100.0, SENSOR_SHORT), (False, 500.0, SENSOR_OPEN)])
def test_out_of_range_reading_names_the_right_fault(uut, ntc, x, bit):
    uut.set("sPar.bSensorNtc", ntc)
    scan(uut, ACTIVE, 95.0, n=2)
    scan(uut, ACTIVE, x)
    alarm = uut.get("fbUut.dwAlarm")
    assert alarm & (SENSOR_OPEN | SENSOR_SHORT) == bit
