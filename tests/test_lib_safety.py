"""Stale-PV watchdog, TUNE abort on a stale or frozen PV, parameter protection (lock, unlock, refusal of
values that switch protection off) and FB_HeaterMonitor on a simulated FOPDT plant."""

from __future__ import annotations

import math

import pytest

from modbus_bridge.plants.base import PlantDisturbance
from modbus_bridge.plants.lti import NLag
from tests.st_helpers import ScanDriver, controller_program, load_test_app
from tests.test_lib_heatup import (
    OVEN_AMBIENT,
    OVEN_K,
    OVEN_L,
    OVEN_N,
    OVEN_T,
    OVEN_W0,
    OVEN_W1,
    oven_two_point,
)

IDLE, ACTIVE, TUNE = 0, 2, 5
STATE_ERROR = 8
STALE_BIT, FROZEN_BIT, OPEN_BIT, STUCK_BIT, DETACHED_BIT = 1 << 22, 1 << 21, 1 << 18, 1 << 20, 1 << 19
TS = 0.1
PROTECTED = 0x007C1041
ERR_TUNE_ABORTED = 21


@pytest.fixture()
def uut() -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", 2.0), ("fTn", 20.0), ("fWatchPeriod", 0.0), ("fRunawayPeriod", 0.0),
                        ("fPvTimeout", 2.0)):
        drv.set(f"sPar.{name}", value)
    drv.set("fbUut.fW1", 100.0)
    return drv


def scan(drv: ScanDriver, mode: int, x: float, n: int = 1, beat: bool = True) -> None:
    drv.set("nMode", mode)
    drv.set("fbUut.fX", x)
    for _ in range(n):
        if beat:
            drv.set("fbUut.nPvSequence", drv.get("fbUut.nPvSequence") + 1)
        drv.scan()


def test_stale_pv_trips_the_watchdog_and_switches_off(uut):
    scan(uut, ACTIVE, 95.0, n=50)
    assert not uut.get("fbUut.dwAlarm") & STALE_BIT
    assert uut.get("fbUut.fY") > 0.0
    scan(uut, ACTIVE, 95.0, n=19, beat=False)
    assert not uut.get("fbUut.dwAlarm") & STALE_BIT, "not before fPvTimeout"
    scan(uut, ACTIVE, 95.0, n=2, beat=False)
    assert uut.get("fbUut.dwAlarm") & STALE_BIT
    assert uut.get("fbUut.fY") == 0.0 and not uut.get("fbUut.bYPWMPos")
    assert uut.get("nState") == STATE_ERROR


@pytest.mark.parametrize("how", ["stale", "frozen"])
def test_tune_aborts_on_a_stale_or_frozen_pv(uut, how):
    uut.set("sPar.fFrozenTime", 5.0)
    x = 20.0
    for k in range(30):  # a live, noisy PV while TUNE waits for a steady X
        scan(uut, TUNE, x + 0.01 * (k % 3))
    assert uut.get("nState") != STATE_ERROR
    scan(uut, TUNE, x, n=60, beat=how == "frozen")
    assert uut.get("nState") == STATE_ERROR
    assert uut.get("fbUut.nErrorId") == ERR_TUNE_ABORTED
    assert uut.get("fbUut.fY") == 0.0
    assert uut.get("fbUut.dwAlarm") & (1 << 17)


def protect(drv: ScanDriver, unlocked: bool) -> None:
    drv.set("fbUut.bProtect", True)
    drv.set("fbUut.bUnlocked", unlocked)


@pytest.mark.parametrize(("field", "value"), [("dwAlarmSupp", 0xFFFFFFFF), ("dwAlarmReaction", 0),
                                               ("eReactionOnFailure", 0), ("fTaskCycleTime", 0.05),
                                               ("fPvTimeout", 0.0), ("fMonitorDwell", 1e9),
                                               ("fXMax", 1e9), ("fTempAbsHigh", 1e9)])
def test_safety_settings_are_locked_without_the_unlock(uut, field, value):
    protect(uut, unlocked=False)
    scan(uut, ACTIVE, 95.0, n=3)
    before = uut.get(f"fbUut.sValid.{field}")
    uut.set(f"sPar.{field}", value)
    scan(uut, ACTIVE, 95.0)
    assert uut.get(f"fbUut.sValid.{field}") == before
    assert uut.get("fbUut.nRefusal") & 2, "refused: locked"
    assert uut.get("fbUut.bParamError")


def test_unlock_accepts_settings_but_never_switching_protection_off(uut):
    protect(uut, unlocked=True)
    scan(uut, ACTIVE, 95.0, n=3)
    uut.set("sPar.dwAlarmSupp", 0x100)  # a tolerance-band warning may be suppressed
    uut.set("sPar.fPvTimeout", 5.0)
    scan(uut, ACTIVE, 95.0)
    assert uut.get("fbUut.sValid.dwAlarmSupp") == 0x100
    assert uut.get("fbUut.sValid.fPvTimeout") == pytest.approx(5.0)
    assert uut.get("fbUut.nRefusal") == 0
    for field, value in (("dwAlarmSupp", 0x1), ("dwAlarmReaction", 0xD07F), ("eReactionOnFailure", 0),
                         ("fPvTimeout", 0.0), ("fFrozenTime", 0.0)):
        good = uut.get(f"fbUut.sValid.{field}")
        uut.set(f"sPar.{field}", value)
        scan(uut, ACTIVE, 95.0)
        assert uut.get(f"fbUut.sValid.{field}") == good, field
        assert uut.get("fbUut.nRefusal") & 4, f"{field}: would switch protection off"
        uut.set(f"sPar.{field}", good)
        scan(uut, ACTIVE, 95.0)
    uut.set("sPar.bReactionNoneAllowed", True)
    scan(uut, ACTIVE, 95.0)
    uut.set("sPar.eReactionOnFailure", 0)
    scan(uut, ACTIVE, 95.0)
    assert uut.get("fbUut.nRefusal") == 0, "reaction NONE with its own explicit setting"


class Fopdt:
    """K e^(-Ls) / (1 + Ts) around an ambient, exact discretisation, Gaussian-free deterministic dither."""

    def __init__(self, k: float, t: float, l: float, ambient: float) -> None:
        self.k, self.t, self.ambient = k, t, ambient
        self.x = ambient
        self.delay = [0.0] * round(l / TS)
        self.n = 0

    def measure(self) -> float:
        self.n += 1
        return self.x + 0.02 * math.sin(self.n * 1.7)

    def step(self, u: float) -> None:
        self.delay.append(u)
        u_del = self.delay.pop(0)
        a = math.exp(-TS / self.t)
        self.x = a * self.x + (1 - a) * (self.ambient + self.k * u_del)


@pytest.mark.parametrize("fault", ["heater_open", "stuck_on", "detached"])
def test_heater_monitor_on_a_simulated_hot_end(uut, fault):
    k, t, l = 0.59, 23.4, 10.6  # seed 003's hot end
    for name, value in (("fKs", k), ("fTg", t), ("fTu", l), ("fKp", 5.3), ("fTn", 22.0),
                        ("fTempAbsHigh", 400.0)):
        uut.set(f"sPar.{name}", value)
    uut.set("fbUut.fW1", 200.0)
    plant = Fopdt(k, t, l, ambient=160.0)
    t_fault = 300.0
    detected = None
    for n in range(round((t_fault + 40.0) / TS)):
        now = n * TS
        x = plant.measure()
        if fault == "detached" and now >= t_fault:
            x = 25.0 + (x - 25.0) * math.exp(-(now - t_fault) / 2.0)
        scan(uut, ACTIVE, x)
        y = uut.get("fbUut.fY")
        alarm = uut.get("fbUut.dwAlarm")
        if now < t_fault:
            monitor_bits = OPEN_BIT | STUCK_BIT | DETACHED_BIT | FROZEN_BIT
            assert not alarm & monitor_bits, f"false alarm at {now:.1f} s"
        elif detected is None and alarm & (OPEN_BIT | STUCK_BIT | DETACHED_BIT):
            detected = (now - t_fault, alarm)
        u = 0.0 if fault == "heater_open" and now >= t_fault else y
        plant.step(100.0 if fault == "stuck_on" and now >= t_fault else u)
    expected = {"heater_open": OPEN_BIT, "stuck_on": STUCK_BIT, "detached": DETACHED_BIT}[fault]
    assert detected is not None, f"{fault} not detected"
    assert detected[1] & expected, f"{fault}: alarm {detected[1]:#x}"
    assert detected[0] <= l + 5.0, f"{fault}: detected after {detected[0]:.1f} s"
    assert uut.get("fbUut.fY") == 0.0


@pytest.mark.parametrize("dead_time", [10.6, 3.0, 0.7, 25.0])
def test_heater_monitor_history_delays_the_output_by_the_model_dead_time(uut, dead_time):
    """The monitor compares X with the output one dead time ago: its history bins are whole task cycles,
    so the delay it applies is L within one bin (L / 44 rounded up to cycles) and the cycle the output
    reaches it in."""
    for name, value in (("fKs", 0.59), ("fTg", 23.4), ("fTu", dead_time)):
        uut.set(f"sPar.{name}", value)
    uut.set("nMode", 4)  # MANUAL: the output is the manual value
    uut.set("fbUut.fYManual", 0.0)
    scan(uut, 4, 160.0, n=round((dead_time + 5.0) / TS))
    uut.set("fbUut.fYManual", 50.0)
    seen = None
    for n in range(round(2.0 * dead_time / TS) + 20):
        scan(uut, 4, 160.0)
        if seen is None and uut.get("fbUut.fbMonitor.fYDelayed") > 25.0:
            seen = (n + 1) * TS
    bin_s = TS * math.ceil(dead_time / (44 * TS))
    assert seen is not None, "the output step never came out of the history"
    assert abs(seen - dead_time) <= bin_s + 2 * TS, \
        f"delay {seen:.1f} s for L = {dead_time} s (bin {bin_s:.1f} s)"


@pytest.mark.parametrize("fault", [None, "stuck_on"])
def test_heater_monitor_follows_a_lag_chain_that_is_faster_than_its_model(uut, fault):
    """The bench oven identified as its 4 equal lags (K 2.2 degC/%, T 45 s, L 4 s; their two-point FOPDT
    has L = 88 s) but 30 % faster: a heat-up pulse (full power 30 s, then the holding power) moves X long
    before the FOPDT's dead time. That is output activity, not more heat than commanded; a heater stuck on
    later is still caught."""
    tu, tg = oven_two_point()
    for name, value in (("fKs", OVEN_K), ("fTg", tg), ("fTu", tu), ("nTuneOrder", OVEN_N),
                        ("fTempAbsHigh", 400.0), ("fWatchPeriod", 0.0), ("fRunawayPeriod", 0.0)):
        uut.set(f"sPar.{name}", value)
    y_rest, y_hold = ((w - OVEN_AMBIENT) / OVEN_K for w in (OVEN_W0, OVEN_W1))
    plant = NLag(gain_c_per_pct=OVEN_K, time_constant_s=0.7 * OVEN_T, order=float(OVEN_N), dead_time_s=OVEN_L,
                 ambient_c=OVEN_AMBIENT, initial_c=OVEN_W0)
    dist = PlantDisturbance.for_channels(1)
    t_pulse, t_fault, horizon = 600.0, 1500.0, 1500.0 + tu + 60.0
    uut.set("fbUut.fYManual", y_rest)
    detected = None
    for step in range(round(horizon / TS)):
        now = step * TS
        if now >= t_pulse:
            uut.set("fbUut.fYManual", 100.0 if now < t_pulse + 30.0 else y_hold)
        scan(uut, 4, plant.temperatures()[0] + 0.02 * math.sin(step * 1.7))  # a live sensor's dither
        alarm = uut.get("fbUut.dwAlarm")
        if fault is None or now < t_fault:
            assert not alarm & (OPEN_BIT | STUCK_BIT | DETACHED_BIT | FROZEN_BIT), \
                f"false alarm {alarm:#x} at {now - t_pulse:.1f} s after the pulse began"
        elif detected is None and alarm & (OPEN_BIT | STUCK_BIT | DETACHED_BIT):
            detected = (now - t_fault, alarm)
        stuck = fault == "stuck_on" and now >= t_fault
        plant.step([100.0 if stuck else uut.get("fbUut.fY")], TS, dist)
    if fault is not None:
        assert detected is not None, f"{fault} not detected"
        assert detected[1] & STUCK_BIT, f"{fault}: alarm {detected[1]:#x}"
        print(f"stuck on detected after {detected[0]:.1f} s (L of the FOPDT {tu:.1f} s)")
        assert detected[0] <= tu, f"{fault}: detected after {detected[0]:.1f} s"
