"""FB_TempController modes, bumpless transfer, setpoint chain and heating/cooling split."""

from __future__ import annotations

import pytest

from tests.st_helpers import ScanDriver, controller_program, load_test_app

IDLE, PASSIVE, ACTIVE, RESET, MANUAL, TUNE = 0, 1, 2, 3, 4, 5
TS = 0.1


@pytest.fixture()
def uut() -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", 2.0), ("fTn", 10.0), ("fTv", 0.0), ("fTd", 0.0), ("fWatchPeriod", 0.0),
                        ("fRunawayPeriod", 0.0)):
        drv.set(f"sPar.{name}", value)
    return drv


def scan(drv: ScanDriver, mode: int, x: float, n: int = 1, w1: float = 50.0) -> float:
    drv.set("nMode", mode)
    drv.set("fbUut.fX", x)
    drv.set("fbUut.fW1", w1)
    drv.scan(n)
    return drv.get("fbUut.fY")


def test_active_p_plus_i(uut: ScanDriver) -> None:
    y = scan(uut, ACTIVE, 45.0)
    assert y == pytest.approx(2.0 * 5.0 + 2.0 * TS / 10.0 * 5.0, rel=1e-4)
    assert uut.get("nState") == ACTIVE


def test_passive_outputs_zero_and_keeps_state(uut: ScanDriver) -> None:
    scan(uut, ACTIVE, 45.0, n=50)
    i_before = uut.get("fbUut.fI")
    assert scan(uut, PASSIVE, 45.0, n=20) == 0.0
    assert uut.get("nState") == PASSIVE
    assert not uut.get("fbUut.bYPWMPos")
    assert uut.get("fbUut.fI") == pytest.approx(i_before)
    y = scan(uut, ACTIVE, 45.0)
    assert y == pytest.approx(10.0 + i_before + 0.1, rel=1e-4)


def test_reset_clears_integrator(uut: ScanDriver) -> None:
    scan(uut, ACTIVE, 45.0, n=50)
    assert uut.get("fbUut.fI") > 4.0
    assert scan(uut, RESET, 45.0) == 0.0
    assert uut.get("nState") == RESET
    assert uut.get("fbUut.fI") == 0.0
    assert scan(uut, ACTIVE, 45.0) == pytest.approx(10.1, rel=1e-4)


def test_manual_and_bumpless_return(uut: ScanDriver) -> None:
    scan(uut, ACTIVE, 45.0, n=20)
    uut.set("fbUut.fYManual", 37.5)
    assert scan(uut, MANUAL, 45.0, n=5) == pytest.approx(37.5)
    assert uut.get("nState") == MANUAL
    y = scan(uut, ACTIVE, 45.0)
    assert y == pytest.approx(37.5, abs=0.2)  # bumpless: only one integral step away
    assert scan(uut, ACTIVE, 45.0) - y == pytest.approx(0.1, rel=1e-3)


def test_manual_value_limited(uut: ScanDriver) -> None:
    uut.set("fbUut.fYManual", 150.0)
    assert scan(uut, MANUAL, 45.0) <= 100.0
    uut.set("fbUut.fYManual", -50.0)
    assert scan(uut, MANUAL, 45.0) == 0.0  # fYMin = 0


def test_setpoint_selection_w2(uut: ScanDriver) -> None:
    uut.set("fbUut.fW2", 30.0)
    uut.set("fbUut.bSelSetpoint", True)
    scan(uut, ACTIVE, 45.0)
    assert uut.get("fbUut.fW") == 30.0
    assert uut.get("fbUut.fE") == pytest.approx(-15.0)


def test_setpoint_ramp(uut: ScanDriver) -> None:
    uut.set("sPar.bEnableRamping", True)
    uut.set("sPar.fWVeloPos", 2.0)
    scan(uut, ACTIVE, 20.0, n=1, w1=50.0)
    assert uut.get("fbUut.fW") == pytest.approx(20.2, rel=1e-4)  # ramp starts at X
    scan(uut, ACTIVE, 20.0, n=99, w1=50.0)
    assert uut.get("fbUut.fW") == pytest.approx(40.0, rel=1e-3)
    scan(uut, ACTIVE, 20.0, n=100, w1=50.0)
    assert uut.get("fbUut.fW") == pytest.approx(50.0)


def test_soft_start_plateau(uut: ScanDriver) -> None:
    for name, value in (("bEnableSoftStart", True), ("fWStartUp", 30.0), ("fTStartUp", 5.0),
                        ("fWStartUpVelo", 10.0)):
        uut.set(f"sPar.{name}", value)
    scan(uut, ACTIVE, 20.0, n=10, w1=80.0)
    assert uut.get("fbUut.fW") == pytest.approx(30.0)
    scan(uut, ACTIVE, 20.0, n=45, w1=80.0)
    assert uut.get("fbUut.fW") == pytest.approx(30.0)  # still holding the plateau
    scan(uut, ACTIVE, 20.0, n=10, w1=80.0)
    assert uut.get("fbUut.fW") == pytest.approx(80.0)


def test_heating_cooling_split_uses_cooling_set(uut: ScanDriver) -> None:
    for name, value in (("fYMin", -100.0), ("fKpCool", 8.0), ("fTnCool", 0.0), ("fTn", 0.0)):
        uut.set(f"sPar.{name}", value)
    y = scan(uut, ACTIVE, 55.0)  # previous output 0: heating set, P = 2 * -5
    assert y == pytest.approx(-10.0)
    y = scan(uut, ACTIVE, 55.0)  # output < 0: cooling set; the new gain enters bumplessly
    assert uut.get("fbUut.bCoolingSet") is True
    assert y == pytest.approx(-10.0)
    y = scan(uut, ACTIVE, 56.0)  # error change -1 with Kp cool 8
    assert y == pytest.approx(-18.0)
    pos = neg = 0
    for _ in range(100):
        scan(uut, ACTIVE, 56.0)
        pos += uut.get("fbUut.bYPWMPos")
        neg += uut.get("fbUut.bYPWMNeg")
    assert pos == 0 and neg == pytest.approx(18, abs=1)


def test_cycle_time_divider(uut: ScanDriver) -> None:
    uut.set("sPar.fCtrlCycleTime", 0.5)
    ys = [scan(uut, ACTIVE, 45.0) for _ in range(10)]
    # the PID runs every 5th call; the integral step is Kp*0.5/Tn*e = 0.5
    assert len(set(round(y, 4) for y in ys)) == 2
    assert ys[-1] - ys[0] == pytest.approx(0.5, rel=1e-3)


def test_time_shim_counts_seconds() -> None:
    from tests.st_helpers import build_program

    prog = build_program("    fSec : REAL;", "  fSec := FC_TimeToSeconds(tValue := T#1250ms);")
    drv = ScanDriver(load_test_app(prog))
    drv.scan()
    assert drv.get("fSec") == pytest.approx(1.25)


@pytest.mark.parametrize("cooling", [False, True], ids=["heating", "cooling"])
def test_the_setpoint_weight_of_the_set_in_use_reaches_the_pid(uut: ScanDriver, cooling: bool) -> None:
    """b = 0 on the set in use: a setpoint step moves the output by the integral step alone."""
    sign = -1.0 if cooling else 1.0
    for name, value in (("fYMin", -100.0), ("fKpCool", 2.0), ("fTnCool", 10.0),
                        ("fSetpointWeight", 1.0 if cooling else 0.0),
                        ("fSetpointWeightCool", 0.0 if cooling else 1.0)):
        uut.set(f"sPar.{name}", value)
    x = 50.0 - sign * 2.0  # an output of sign * 4 % and more: the set of that side is in use
    y0 = scan(uut, ACTIVE, x, n=3, w1=50.0)
    assert uut.get("fbUut.bCoolingSet") is cooling
    y = scan(uut, ACTIVE, x, w1=50.0 + sign * 10.0)
    step_i = 2.0 * TS / 10.0
    assert y - y0 == pytest.approx(step_i * (sign * 2.0 + sign * 10.0), rel=1e-3)  # no P step of 20 %


def test_amigo_weight_zero_cuts_the_overshoot_of_a_small_setpoint_step() -> None:
    """Seed 003's hot end with its AMIGO set (reference/control.md): a 2 degC step overshoots far less with
    b = 0 than with the setpoint on the whole P part, and both settle on W."""
    from tests.test_lib_tuner import RULE_AMIGO, Fopdt, rule_values

    k, t, l = 0.5916, 23.4, 10.6
    kp, tn, tv, td = rule_values(RULE_AMIGO, k, l, t, vmax=0.0, dy=0.0)
    peaks = {}
    for weight in (1.0, 0.0):
        drv = ScanDriver(load_test_app(controller_program()))
        for name, value in (("fKp", kp), ("fTn", tn), ("fTv", tv), ("fTd", td), ("fWatchPeriod", 0.0),
                            ("fRunawayPeriod", 0.0), ("fSetpointWeight", weight)):
            drv.set(f"sPar.{name}", value)
        plant = Fopdt(k=k, t=t, l=l, x0=160.0, dt=TS)
        w, xs = 160.0 + k * 50.0, []
        for n in range(round(600 / TS)):
            if n == round(300 / TS):
                w += 2.0
            y = scan(drv, ACTIVE, plant.x, w1=w)
            plant.step(y)
            xs.append(plant.x)
        step = xs[round(300 / TS):]
        assert step[-1] == pytest.approx(w, abs=0.01)
        peaks[weight] = (max(step) - w) / 2.0 * 100.0
    print(f"overshoot of a 2 degC step: b = 1 {peaks[1.0]:.1f} %, b = 0 {peaks[0.0]:.1f} %")
    assert peaks[0.0] < 0.5 * peaks[1.0]


def step_response(kp: float, tn: float, weight: float, k: float, t: float, l: float, x_rest: float,
                  dw: float, seconds: float) -> list[float]:
    """X after a setpoint step of dw from rest at x_rest (ambient 25 degC), the PID at that rest."""
    from tests.test_lib_tuner import Fopdt

    drv = ScanDriver(load_test_app(controller_program()))
    for name, value in (("fKp", kp), ("fTn", tn), ("fTv", 0.0), ("fTd", 0.0), ("fWatchPeriod", 0.0),
                        ("fRunawayPeriod", 0.0), ("fSetpointWeight", weight), ("fWMax", 1000.0),
                        ("fXMax", 2000.0), ("fTempAbsHigh", 2000.0)):
        drv.set(f"sPar.{name}", value)
    plant = Fopdt(k=k, t=t, l=l, x0=25.0, dt=TS)
    plant.x = x_rest
    plant.line.clear()
    plant.line.extend([(x_rest - 25.0) / k] * round(l / TS))
    drv.set("fbUut.fYManual", (x_rest - 25.0) / k)
    scan(drv, MANUAL, plant.x, w1=x_rest)
    for _ in range(round(10.0 / TS)):  # the bumpless hand-over, then at rest on W
        plant.step(scan(drv, ACTIVE, plant.x, w1=x_rest))
    xs = []
    for _ in range(round(seconds / TS)):
        plant.step(scan(drv, ACTIVE, plant.x, w1=x_rest + dw))
        xs.append(plant.x)
    return xs


def test_simc_weight_takes_a_small_step_without_overshoot_and_a_saturating_one_as_fast() -> None:
    """T1's hot end (K 3.4 degC/%, T 140 s, L 5.5 s) with SIMC PI and the weight SIMC writes: a 5 degC step,
    which leaves the output off its limit, overshoots by about a fifth with b = 1 and hardly at all with
    the weight, and settles sooner; a 40 degC step saturates the output, and the weight's filter restarts
    at the limit, so it rises exactly as with b = 1."""
    from tests.test_lib_tuner import RULE_SIMC, rule_values, setpoint_weight

    k, t, l = 3.4, 140.0, 5.5
    kp, tn, _, _ = rule_values(RULE_SIMC, k, l, t, vmax=0.0, dy=0.0)
    weight = setpoint_weight(RULE_SIMC, l / (l + t), tn, t)
    assert 0.7 < weight < 0.85
    small = {b: step_response(kp, tn, b, k, t, l, 200.0, 5.0, 200.0) for b in (1.0, weight)}
    overshoot = {b: (max(xs) - 205.0) / 5.0 * 100.0 for b, xs in small.items()}
    settled = {b: TS * (1 + max(i for i, x in enumerate(xs) if abs(x - 205.0) > 0.1))
               for b, xs in small.items()}
    print(f"5 degC step: b = 1 {overshoot[1.0]:.1f} % / {settled[1.0]:.0f} s, "
          f"b = {weight:.2f} {overshoot[weight]:.2f} % / {settled[weight]:.0f} s")
    assert overshoot[1.0] > 15.0
    assert overshoot[weight] < 1.5
    assert settled[weight] < 0.5 * settled[1.0]
    large = {b: step_response(kp, tn, b, k, t, l, 200.0, 40.0, 150.0) for b in (1.0, weight)}
    assert max(large[1.0]) < 240.0 * 1.01
    assert large[weight] == pytest.approx(large[1.0], abs=1e-3)
