"""Alarm word of FB_TempController: every bit set, latched, acknowledged; suppression; reactions."""

from __future__ import annotations

import math

import pytest

from tests.st_helpers import ScanDriver, controller_program, load_test_app

PASSIVE, ACTIVE = 1, 2
STATE_ACTIVE, STATE_ERROR = 2, 8
TS = 0.1


@pytest.fixture()
def uut() -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", 2.0), ("fTn", 50.0), ("fTempAbsHigh", 150.0), ("fTempAbsLow", 0.0),
                        ("fXMin", -50.0), ("fXMax", 400.0), ("eReactionOnFailure", None)):
        if value is not None:
            drv.set(f"sPar.{name}", value)
    drv.set("fbUut.fW1", 50.0)
    return drv


def scan(drv: ScanDriver, x: float, n: int = 1, mode: int = ACTIVE) -> int:
    drv.set("nMode", mode)
    drv.set("fbUut.fX", x)
    drv.scan(n)
    return drv.get("fbUut.dwAlarm")


def ack(drv: ScanDriver, x: float) -> int:
    drv.set("fbUut.bAckAlarm", True)
    alarm = scan(drv, x)
    drv.set("fbUut.bAckAlarm", False)
    scan(drv, x)
    return alarm


def check_latch_and_ack(drv: ScanDriver, bit: int, bad_x: float, good_x: float) -> None:
    assert not scan(drv, good_x) & bit
    assert scan(drv, bad_x) & bit
    assert scan(drv, good_x) & bit, "latched until acknowledged"
    assert not ack(drv, good_x) & bit


@pytest.mark.parametrize(
    ("inp", "bit"),
    [("bOpenThermocouple", 0x1), ("bReverseThermocouple", 0x2), ("bBackVoltage", 0x4), ("bLeakage", 0x8),
     ("bShortCircuit", 0x10), ("bOpenCircuit", 0x20), ("bSensorShort", 0x40)],
)
def test_hardware_inputs(uut: ScanDriver, inp: str, bit: int) -> None:
    scan(uut, 50.0)
    uut.set(f"fbUut.{inp}", True)
    assert scan(uut, 50.0) & bit
    uut.set(f"fbUut.{inp}", False)
    assert scan(uut, 50.0) & bit
    assert not ack(uut, 50.0) & bit  # the rising edge of bAckAlarm clears it: the cause is gone
    assert not scan(uut, 50.0) & bit


def test_sensor_open_short_from_value(uut: ScanDriver) -> None:
    check_latch_and_ack(uut, 0x1, 500.0, 50.0)
    check_latch_and_ack(uut, 0x1, math.nan, 50.0)
    check_latch_and_ack(uut, 0x40, -100.0, 50.0)


def test_nan_x_never_reaches_output(uut: ScanDriver) -> None:
    scan(uut, 40.0, n=10)
    scan(uut, math.nan, n=5)
    y = uut.get("fbUut.fY")
    assert math.isfinite(y) and 0.0 <= y <= 100.0
    assert uut.get("nState") == STATE_ERROR


def test_tolerance_bands_armed_after_reaching_band(uut: ScanDriver) -> None:
    # far below W at start: bands not armed yet
    assert scan(uut, 20.0, n=5) & 0xF00 == 0
    scan(uut, 49.0, n=5)  # inside the first band, but not long enough: a normal approach
    assert scan(uut, 44.0) & 0xF00 == 0, "not armed before fBandArmTime in the band"
    assert scan(uut, 56.0) & 0xF00 == 0, "an overshoot right after entering the band is no warning"
    scan(uut, 49.0, n=round(30.0 / TS))  # settled inside the first band for fBandArmTime: armed
    assert scan(uut, 44.0) & 0x300 == 0x100      # below W - 5
    assert scan(uut, 39.0) & 0x300 == 0x300      # below W - 10
    assert scan(uut, 56.0) & 0xC00 == 0x400      # above W + 5
    assert scan(uut, 61.0) & 0xC00 == 0xC00      # above W + 10
    scan(uut, 50.0)
    assert scan(uut, 50.0) & 0xF00 == 0xF00  # latched
    assert ack(uut, 50.0) & 0xF00 == 0


def test_tolerance_bands_arm_after_dead_times_on_a_slow_plant(uut: ScanDriver) -> None:
    uut.set("sPar.fTu", 20.0)  # identified dead time: arm after MAX(30 s, 4 x 20 s) = 80 s in the band
    uut.set("sPar.fFrozenTime", 0.0)  # a constant test input is no frozen sensor here
    scan(uut, 20.0, n=5)
    scan(uut, 49.0, n=round(60.0 / TS))  # longer than fBandArmTime, shorter than 4 dead times
    assert scan(uut, 44.0) & 0xF00 == 0, "a swing through the band on a slow loop is no warning"
    scan(uut, 49.0, n=round(85.0 / TS))  # the swing above restarted the time in the band
    assert scan(uut, 44.0) & 0x300 == 0x100, "armed after 4 dead times in the band"


def test_absolute_limits(uut: ScanDriver) -> None:
    check_latch_and_ack(uut, 0x1000, 160.0, 50.0)
    check_latch_and_ack(uut, 0x2000, -5.0, 50.0)


def test_thermal_runaway_at_temperature(uut: ScanDriver) -> None:
    uut.set("sPar.fRunawayHysteresis", 4.0)
    uut.set("sPar.fRunawayPeriod", 10.0)
    scan(uut, 50.0, n=5)  # at temperature: armed
    assert not scan(uut, 45.0, n=round(9.0 / TS)) & 0x4000
    assert scan(uut, 45.0, n=round(2.0 / TS)) & 0x4000
    assert scan(uut, 50.0) & 0x4000
    assert not ack(uut, 50.0) & 0x4000


def test_runaway_not_flagged_while_x_trails_a_setpoint_ramped_from_outside(uut: ScanDriver) -> None:
    uut.set("sPar.fRunawayHysteresis", 4.0)
    uut.set("sPar.fRunawayPeriod", 10.0)
    uut.set("sPar.fTempAbsHigh", 300.0)
    scan(uut, 50.0, n=5)  # at temperature: armed
    w, x = 50.0, 50.0
    for _ in range(round(60 / TS)):  # W ramped by a client at 0.1 degC/s, X follows 6 degC behind
        w += 0.1 * TS
        x = w - 6.0
        uut.set("fbUut.fW1", w)
        assert not scan(uut, x) & 0x4000
    for _ in range(round(15 / TS)):  # ramp over, X stuck below the reached W: runaway after the period
        alarm = scan(uut, x)
    assert not alarm & 0x4000, "X never reached the new W - hysteresis: the check is not armed yet"
    alarm = scan(uut, w - 1.0, n=3)  # reaches W: armed again
    assert not alarm & 0x4000
    assert scan(uut, w - 6.0, n=round(11 / TS)) & 0x4000


def test_heat_up_watch(uut: ScanDriver) -> None:
    uut.set("sPar.fWatchPeriod", 20.0)
    uut.set("sPar.fWatchIncrease", 2.0)
    uut.set("fbUut.fW1", 200.0)
    uut.set("sPar.fTempAbsHigh", 300.0)
    x = 20.0
    for _ in range(round(60 / TS)):  # rising 0.2 degC/s at full output: no alarm
        x += 0.2 * TS
        assert not scan(uut, x) & 0x8000
    # stalled: the 20 s window restarted at the last +2 degC (at most 10 s before the stall)
    assert not scan(uut, x, n=round(9 / TS)) & 0x8000
    assert scan(uut, x, n=round(12 / TS)) & 0x8000


def test_parameter_error_bit(uut: ScanDriver) -> None:
    uut.set("sPar.fKp", math.nan)
    assert scan(uut, 50.0) & 0x10000
    uut.set("sPar.fKp", 2.0)
    assert scan(uut, 50.0) & 0x10000
    assert not ack(uut, 50.0) & 0x10000


def test_suppression_mask_hides_bits(uut: ScanDriver) -> None:
    uut.set("sPar.dwAlarmSupp", 0x1000)
    assert not scan(uut, 160.0) & 0x1000
    assert uut.get("nState") == STATE_ACTIVE


def test_no_latch_clears_by_itself(uut: ScanDriver) -> None:
    uut.set("sPar.bAlarmLatch", False)
    assert scan(uut, 160.0) & 0x1000
    assert not scan(uut, 50.0) & 0x1000


@pytest.mark.parametrize(("reaction", "expected"), [(1, 0.0), (2, 33.0), (3, None)])
def test_reaction_on_failure(uut: ScanDriver, reaction: int, expected: float | None) -> None:
    uut.set("sPar.fYOnFailure", 33.0)
    scan(uut, 40.0, n=20)
    y_before = uut.get("fbUut.fY")
    uut.set("sPar.eReactionOnFailure", reaction)
    scan(uut, 160.0, n=3)  # absolute high: in the default reaction mask
    assert uut.get("nState") == STATE_ERROR
    assert uut.get("fbUut.bError") is True
    assert uut.get("fbUut.nErrorId") == 20
    want = y_before if expected is None else expected
    assert uut.get("fbUut.fY") == pytest.approx(want, abs=1e-4)
    scan(uut, 40.0)
    ack(uut, 40.0)
    assert uut.get("nState") == STATE_ACTIVE


def test_reaction_none_keeps_controlling(uut: ScanDriver) -> None:
    uut.set("sPar.eReactionOnFailure", 0)
    assert scan(uut, 160.0) & 0x1000
    assert uut.get("nState") == STATE_ACTIVE
