"""FB_CtrlPid's setpoint weight b (docs/library.md, "PID"): the setpoint reaches P and I through
F(s) = b + (1 - b)/(1 + Tn s), which in discrete time moves the output exactly as Kp (b W - X) plus the
integral of the whole error would, keeps no offset at rest and changes bumplessly."""

from __future__ import annotations

import math

import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app
from tests.test_lib_pid import REL, TS, configure, run


@pytest.fixture(scope="module")
def pid() -> ScanDriver:
    prog = build_program("    fbPid : FB_CtrlPid;", "  fbPid();")
    return ScanDriver(load_test_app(prog))


@pytest.mark.parametrize("weight", [0.0, 0.3, 1.0])
def test_a_setpoint_step_moves_the_output_as_the_weighted_form_does(pid: ScanDriver, weight: float) -> None:
    kp, tn, dw = 2.0, 5.0, 10.0
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, weight=weight)
    y0 = run(pid, 20.0, [20.0] * 3)[-1]
    ys = run(pid, 20.0 + dw, [20.0] * 20)
    # Kp (b W - X) + Kp Ts/Tn sum(W - X): the P part takes b of the step, the integral all of it
    expected = [y0 + kp * weight * dw + kp * TS / tn * dw * k for k in range(1, 21)]
    assert ys == pytest.approx(expected, rel=REL, abs=1e-4)


def test_at_rest_the_weight_leaves_no_offset_and_the_integral_holds_the_hold_power(pid: ScanDriver) -> None:
    """A loop on a static plant X = gain * Y settles on W with any b, and I ends at the holding output."""
    kp, tn, gain = 1.5, 4.0, 0.5
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, ymin=0.0, ymax=100.0, weight=0.0)
    pid.set("fbPid.fW", 20.0)
    y = 0.0
    for _ in range(2000):
        pid.set("fbPid.fX", gain * y)
        pid.scan()
        y = pid.get("fbPid.fY")
    assert gain * y == pytest.approx(20.0, abs=1e-3)
    assert pid.get("fbPid.fI") == pytest.approx(40.0, abs=1e-2)  # not 40 % plus Kp * W


def test_a_new_weight_mid_response_does_not_move_the_output(pid: ScanDriver) -> None:
    kp, tn = 3.0, 20.0
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, weight=0.0)
    run(pid, 50.0, [50.0] * 3)
    ys = run(pid, 60.0, [50.0] * 5)  # the filtered setpoint is still far from 60
    pid.set("fbPid.fSetpointWeight", 1.0)  # P on the whole error would add about 3 * 10 * 0.98 %
    y_after = run(pid, 60.0, [50.0])[0]
    assert abs(y_after - ys[-1]) < 3 * abs(ys[-1] - ys[-2])


def test_a_setpoint_change_during_a_hold_is_not_filtered_afterwards(pid: ScanDriver) -> None:
    kp, tn = 2.0, 10.0
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, weight=0.0)
    y0 = run(pid, 20.0, [20.0] * 3)[-1]
    pid.set("fbPid.bHold", True)
    run(pid, 30.0, [20.0] * 3)
    pid.set("fbPid.bHold", False)
    y = run(pid, 30.0, [20.0])[0]
    assert y == pytest.approx(y0 + kp * 10.0 + kp * TS / tn * 10.0, rel=REL)


@pytest.mark.parametrize("weight", [-0.5, 1.5])
def test_a_weight_outside_zero_to_one_is_limited(pid: ScanDriver, weight: float) -> None:
    kp, tn = 2.0, 10.0
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, weight=weight)
    y0 = run(pid, 20.0, [20.0] * 2)[-1]
    y = run(pid, 30.0, [20.0])[0]
    p_share = min(max(weight, 0.0), 1.0)
    assert y == pytest.approx(y0 + kp * 10.0 * p_share + kp * TS / tn * 10.0, rel=REL, abs=1e-5)


def test_a_non_finite_weight_changes_no_state(pid: ScanDriver) -> None:
    configure(pid, kp=2.0, tn=10.0, tv=0.0, td=0.0, weight=0.5)
    y = run(pid, 30.0, [20.0] * 3)[-1]
    i = pid.get("fbPid.fI")
    pid.set("fbPid.fSetpointWeight", math.nan)
    assert run(pid, 30.0, [20.0])[0] == y
    assert pid.get("fbPid.bInputError") is True
    assert pid.get("fbPid.fI") == i
    pid.set("fbPid.fSetpointWeight", 1.0)
