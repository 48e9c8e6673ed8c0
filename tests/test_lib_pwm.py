"""FB_CtrlPwm: duty averaging with carry, minimum on/off times."""

from __future__ import annotations

import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app

TS = 0.1
PERIOD = 1.0


@pytest.fixture(scope="module")
def pwm() -> ScanDriver:
    return ScanDriver(load_test_app(build_program("    fbPwm : FB_CtrlPwm;", "  fbPwm();")))


def run(drv: ScanDriver, duty: float, periods: int, min_on: float = 0.0, min_off: float = 0.0) -> list[bool]:
    for name, value in (("fDuty", duty), ("fPeriod", PERIOD), ("fMinOn", min_on), ("fMinOff", min_off),
                        ("fCycleTime", TS)):
        drv.set(f"fbPwm.{name}", value)
    bits = []
    for _ in range(round(periods * PERIOD / TS)):
        drv.scan()
        bits.append(drv.get("fbPwm.bOut"))
    return bits


def runs(bits: list[bool]) -> list[tuple[bool, int]]:
    out: list[tuple[bool, int]] = []
    for b in bits:
        if out and out[-1][0] == b:
            out[-1] = (b, out[-1][1] + 1)
        else:
            out.append((b, 1))
    return out


@pytest.mark.parametrize("duty", [0.7, 3.3, 25.0, 50.5, 77.7, 99.2])
def test_average_duty_within_half_percent(pwm: ScanDriver, duty: float) -> None:
    run(pwm, duty, 3)  # settle the carry from the previous case
    bits = run(pwm, duty, 400)
    assert 100.0 * sum(bits) / len(bits) == pytest.approx(duty, abs=0.5)


@pytest.mark.parametrize("duty", [4.0, 12.0, 88.0, 97.0])
def test_minimum_on_and_off_times_with_carry(pwm: ScanDriver, duty: float) -> None:
    run(pwm, duty, 3, min_on=0.3, min_off=0.3)
    bits = run(pwm, duty, 400, min_on=0.3, min_off=0.3)
    assert 100.0 * sum(bits) / len(bits) == pytest.approx(duty, abs=0.5)
    interior = runs(bits)[1:-1]
    assert interior, "no switching at all"
    assert min(n for on, n in interior if on) * TS >= 0.3 - 1e-9
    assert min(n for on, n in interior if not on) * TS >= 0.3 - 1e-9


def test_full_and_zero_are_steady(pwm: ScanDriver) -> None:
    assert all(run(pwm, 100.0, 5))
    assert not any(run(pwm, 0.0, 5))
