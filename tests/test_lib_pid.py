"""FB_CtrlPid against hand-computed sequences (docs/library.md, "PID")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app

TS = 0.1
REL = 1e-4


@dataclass
class RefPid:
    """Independent Python model of the documented equations."""

    kp: float
    tn: float
    tv: float
    td: float
    ymin: float = -100.0
    ymax: float = 100.0
    ts: float = TS
    i: float = 0.0
    d: float = 0.0
    x_prev: float | None = None
    kp_prev: float | None = None

    def step(self, w: float, x: float) -> float:
        e = w - x
        if self.x_prev is None:
            self.x_prev, self.kp_prev = x, self.kp
        if self.kp != self.kp_prev:
            old_sum = self.kp_prev * e + self.i + self.d
            if old_sum < self.ymin:  # saturated: I moves only as far as the output would leave the limit
                self.i = min(self.i, self.ymin - self.kp * e - self.d)
            elif old_sum > self.ymax:
                self.i = max(self.i, self.ymax - self.kp * e - self.d)
            else:
                self.i -= (self.kp - self.kp_prev) * e
        p = self.kp * e
        d = 0.0
        if self.tv > 0:
            den = self.td + self.ts
            d = self.td / den * self.d - self.kp * self.tv / den * (x - self.x_prev)
        di = self.kp * self.ts / self.tn * e if self.tn > 0 else 0.0
        i_new = self.i + di
        if di > 0:
            i_new = min(i_new, max(self.i, self.ymax - p - d))
        elif di < 0:
            i_new = max(i_new, min(self.i, self.ymin - p - d))
        self.i, self.d, self.x_prev, self.kp_prev = i_new, d, x, self.kp
        return min(max(p + i_new + d, self.ymin), self.ymax)


@pytest.fixture(scope="module")
def pid() -> ScanDriver:
    prog = build_program("    fbPid : FB_CtrlPid;", "  fbPid();")
    return ScanDriver(load_test_app(prog))


def configure(drv: ScanDriver, kp: float, tn: float, tv: float, td: float,
              ymin: float = -100.0, ymax: float = 100.0, ipart_only: bool = False,
              weight: float = 1.0, weight_min_step: float = 0.0) -> None:
    for name, value in (("fKp", kp), ("fTn", tn), ("fTv", tv), ("fTd", td), ("fYMin", ymin),
                        ("fYMax", ymax), ("fCycleTime", TS), ("fSetpointWeight", weight),
                        ("fWeightMinStep", weight_min_step)):
        drv.set(f"fbPid.{name}", value)
    drv.set("fbPid.bARWOnIPartOnly", ipart_only)
    drv.set("fbPid.bSync", False)
    drv.set("fbPid.bHold", False)
    drv.set("fbPid.bReset", True)
    drv.scan()
    drv.set("fbPid.bReset", False)


def run(drv: ScanDriver, w: float, xs: list[float]) -> list[float]:
    out = []
    drv.set("fbPid.fW", w)
    for x in xs:
        drv.set("fbPid.fX", x)
        drv.scan()
        out.append(drv.get("fbPid.fY"))
    return out


def test_p_step_is_kp_times_error(pid: ScanDriver) -> None:
    configure(pid, kp=4.0, tn=0.0, tv=0.0, td=0.0)
    ys = run(pid, 30.0, [20.0, 25.0, 28.5])
    assert ys == pytest.approx([40.0, 20.0, 6.0], rel=REL)


def test_integral_ramp_by_kp_ts_over_tn(pid: ScanDriver) -> None:
    configure(pid, kp=2.0, tn=10.0, tv=0.0, td=0.0)
    ys = run(pid, 21.0, [20.0] * 5)
    # P = 2, I grows by Kp*Ts/Tn*e = 0.02 per cycle, starting with the first cycle
    assert ys == pytest.approx([2.02, 2.04, 2.06, 2.08, 2.10], rel=REL)


def test_filtered_derivative_on_measurement(pid: ScanDriver) -> None:
    kp, tv, td = 2.0, 5.0, 1.0
    configure(pid, kp=kp, tn=0.0, tv=tv, td=td)
    xs = [20.0, 20.0, 21.0, 22.0, 22.0, 22.0]
    ys = run(pid, 20.0, xs)
    ref = RefPid(kp, 0.0, tv, td)
    expected = [ref.step(20.0, x) for x in xs]
    assert ys == pytest.approx(expected, rel=REL, abs=1e-5)
    # hand values: D-T1 backward Euler, a = Td/(Td+Ts) = 1/1.1, gain Kp*Tv/(Td+Ts) = 10/1.1
    d3 = -10.0 / 1.1 * 1.0
    assert ys[2] == pytest.approx(kp * (20.0 - 21.0) + d3, rel=REL)
    assert ys[4] == pytest.approx(kp * (20.0 - 22.0) + (1 / 1.1) * ((1 / 1.1) * d3 - 10.0 / 1.1), rel=REL)


def test_no_derivative_kick_on_setpoint_step(pid: ScanDriver) -> None:
    configure(pid, kp=1.0, tn=0.0, tv=10.0, td=1.0)
    run(pid, 20.0, [20.0, 20.0])
    ys = run(pid, 30.0, [20.0])
    assert ys[0] == pytest.approx(10.0, rel=REL)  # only P: no D on the setpoint


def test_anti_windup_stops_integrator_at_limit(pid: ScanDriver) -> None:
    configure(pid, kp=5.0, tn=1.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0)
    ys = run(pid, 100.0, [70.0] * 50)  # P = 150: saturated at once
    assert max(ys) == pytest.approx(100.0)
    assert pid.get("fbPid.bARWActive") is True
    i_sat = pid.get("fbPid.fI")
    assert i_sat <= 1e-6  # the integrator did not wind up while P alone saturates the output
    # error reverses: output leaves the limit immediately (no windup to unwind)
    ys = run(pid, 100.0, [99.0, 101.0])
    assert ys[-1] < 5.0
    ref_unclamped_i = 50 * 5.0 * TS / 1.0 * 30.0
    assert ref_unclamped_i > 100.0  # a plain integrator would have wound up far beyond the limit


def test_anti_windup_ipart_only_clamps_i_to_limits(pid: ScanDriver) -> None:
    configure(pid, kp=1.0, tn=1.0, tv=0.0, td=0.0, ymin=0.0, ymax=50.0, ipart_only=True)
    run(pid, 100.0, [90.0] * 200)
    assert pid.get("fbPid.fI") == pytest.approx(50.0, rel=REL)
    assert pid.get("fbPid.fY") == pytest.approx(50.0, rel=REL)


def test_reference_sequence_matches_with_limits(pid: ScanDriver) -> None:
    kp, tn, tv, td = 3.0, 8.0, 2.0, 0.5
    configure(pid, kp=kp, tn=tn, tv=tv, td=td, ymin=-20.0, ymax=60.0)
    ref = RefPid(kp, tn, tv, td, ymin=-20.0, ymax=60.0)
    xs = [20.0 + 0.3 * k for k in range(60)] + [38.0 - 0.5 * k for k in range(60)]
    ys = run(pid, 30.0, xs)
    expected = [ref.step(30.0, x) for x in xs]
    assert ys == pytest.approx(expected, rel=1e-3, abs=1e-3)


def test_gain_change_does_not_jump_output(pid: ScanDriver) -> None:
    configure(pid, kp=2.0, tn=20.0, tv=0.0, td=0.0)
    ys = run(pid, 50.0, [40.0] * 10)
    step_per_cycle = ys[-1] - ys[-2]
    pid.set("fbPid.fKp", 6.0)  # P alone would jump by 4 * 10 = 40 %
    y_after = run(pid, 50.0, [40.0])[0]
    # the only change is the integral step, now with the new gain: 6 * 0.1 / 20 * 10 = 0.3
    assert y_after - ys[-1] == pytest.approx(0.3, rel=1e-3)
    assert abs(y_after - ys[-1]) < 40.0 * 0.05
    assert step_per_cycle == pytest.approx(0.1, rel=1e-3)


def test_integral_off_when_tn_not_positive(pid: ScanDriver) -> None:
    configure(pid, kp=1.0, tn=-5.0, tv=0.0, td=0.0)
    ys = run(pid, 30.0, [20.0] * 5)
    assert ys == pytest.approx([10.0] * 5, rel=REL)


def test_sync_presets_output_and_hold_freezes(pid: ScanDriver) -> None:
    configure(pid, kp=2.0, tn=10.0, tv=0.0, td=0.0)
    pid.set("fbPid.bSync", True)
    pid.set("fbPid.fSyncValue", 42.0)
    ys = run(pid, 30.0, [20.0])
    assert ys[0] == pytest.approx(42.0)
    pid.set("fbPid.bSync", False)
    ys = run(pid, 30.0, [20.0])
    assert ys[0] == pytest.approx(42.0 + 2.0 * 0.1 / 10.0 * 10.0, rel=REL)  # continues from 42 % bumplessly
    pid.set("fbPid.bHold", True)
    ys = run(pid, 30.0, [10.0, 0.0])
    assert ys == pytest.approx([ys[0], ys[0]]) and ys[0] == pytest.approx(42.2, rel=REL)


def test_gain_change_in_saturation_leaves_the_integrator(pid: ScanDriver) -> None:
    """A long saturation with a falling Kp (a gain scheduler on a large error) must not wind I down."""
    configure(pid, kp=3.5, tn=50.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0)
    run(pid, 100.0, [100.0] * 5)  # at rest, I = 0
    run(pid, 100.0, [250.0] * 3)  # cooling down from far above: P = -525 %, output pinned at 0 %
    i_before = pid.get("fbPid.fI")
    for kp in (3.3, 3.0, 2.7):
        pid.set("fbPid.fKp", kp)
        assert run(pid, 100.0, [250.0])[-1] == 0.0
    assert pid.get("fbPid.fI") == pytest.approx(i_before, abs=1e-6)
    # without the saturation rule the absorption would have moved I by -(2.7 - 3.5) * -150 = -120 %


def test_gain_change_off_the_limit_stays_bumpless(pid: ScanDriver) -> None:
    configure(pid, kp=2.0, tn=50.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0)
    run(pid, 100.0, [100.0] * 3)
    pid.set("fbPid.fI", 40.0)
    y0 = run(pid, 100.0, [95.0])[-1]  # 2 * 5 + 40 + I step
    pid.set("fbPid.fKp", 3.0)
    y1 = run(pid, 100.0, [95.0])[-1]
    assert y1 - y0 == pytest.approx(3.0 * 0.1 / 50.0 * 5.0, rel=1e-4)  # only the new gain's I step


def _scheduled(pid: ScanDriver, kp: float, scale: float) -> None:
    pid.set("fbPid.fKpScale", scale)
    pid.set("fbPid.fKp", kp * scale)


def test_a_schedulers_factor_moves_p_and_a_new_base_is_absorbed(pid: ScanDriver) -> None:
    """fKpScale: a change of the factor alone moves P by the change times e (the scheduler's own bound keeps
    it small); a new base at the same call is absorbed whole, as any gain change without a scheduler."""
    configure(pid, kp=2.0, tn=50.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0)
    pid.set("fbPid.fKpScale", 1.0)
    run(pid, 100.0, [100.0] * 3)
    pid.set("fbPid.fI", 40.0)
    y0 = run(pid, 100.0, [95.0])[-1]
    _scheduled(pid, 2.0, 1.25)  # the factor alone: P moves by 2 * 0.25 * 5 = 2.5 %
    y1 = run(pid, 100.0, [95.0])[-1]
    assert y1 - y0 == pytest.approx(2.5 + 2.5 * 0.1 / 50.0 * 5.0, rel=1e-4)
    _scheduled(pid, 3.0, 1.0)  # a new base (the tuner, an HMI) with the factor reset: bumpless
    y2 = run(pid, 100.0, [95.0])[-1]
    assert y2 - y1 == pytest.approx(3.0 * 0.1 / 50.0 * 5.0, rel=1e-4)
    pid.set("fbPid.fKpScale", 1.0)


def test_a_factor_that_follows_every_adc_count_leaves_no_drift(pid: ScanDriver) -> None:
    """X flips between two ADC counts around W while the scheduler's factor depends on the flip's direction
    (a fuzzy table reading the slope): in the velocity form every up-and-down pair would leave
    (Kp(up) - Kp(down)) * count in the output; with the factor in P the output returns to where it was."""
    configure(pid, kp=30.0, tn=0.0, tv=0.0, td=0.0, ymin=-100.0, ymax=100.0)
    pid.set("fbPid.fKpScale", 1.0)
    run(pid, 2.0, [2.0] * 3)
    pid.set("fbPid.fI", -40.0)
    count = 0.029
    y_start = run(pid, 2.0, [2.0])[-1]
    for _ in range(50):
        _scheduled(pid, 30.0, 1.2)  # X one count down (e > 0): the table raises Kp
        run(pid, 2.0, [2.0 - count])
        _scheduled(pid, 30.0, 0.8)  # back up: the table lowers it
        run(pid, 2.0, [2.0])
    assert run(pid, 2.0, [2.0])[-1] == pytest.approx(y_start, abs=1e-3)
    # absorbed, each pair would have moved the output by (1.2 - 0.8) * 30 * 0.029 = 0.35 %: 17 % in 50 pairs
    pid.set("fbPid.fKpScale", 1.0)


# setpoint weight b: the setpoint reaches P and I through F(s) = b + (1 - b)/(1 + Tn s), which in discrete
# time moves the output exactly as Kp (b W - X) plus the integral of the whole error would

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


def test_a_step_that_saturates_its_weighted_p_part_leaves_the_limit_as_with_b_one(pid: ScanDriver) -> None:
    """At the limit the weight changes nothing the plant sees, and its filter restarts at W: once X comes
    close the output is the b = 1 output, not one still holding back (1 - b) of the step for a Tn."""
    xs = [20.0 + 0.5 * k for k in range(200)] + [119.5] * 50
    runs = {}
    for weight in (1.0, 0.4):
        configure(pid, kp=4.0, tn=20.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0, weight=weight)
        run(pid, 20.0, [20.0] * 3)
        runs[weight] = run(pid, 120.0, xs)
    assert runs[0.4][0] == 100.0 and min(runs[1.0]) < 100.0
    assert runs[0.4] == pytest.approx(runs[1.0], rel=REL, abs=1e-4)


def test_a_step_that_saturates_only_the_whole_p_part_keeps_its_weight(pid: ScanDriver) -> None:
    kp, tn, dw, weight = 2.0, 20.0, 40.0, 0.4  # b = 1 would ask 80 % + I above the 50 % limit
    configure(pid, kp=kp, tn=tn, tv=0.0, td=0.0, ymin=0.0, ymax=50.0, weight=weight)
    y0 = run(pid, 20.0, [20.0] * 3)[-1]
    ys = run(pid, 20.0 + dw, [20.0] * 5)
    expected = [y0 + kp * weight * dw + kp * TS / tn * dw * k for k in range(1, 6)]
    assert ys == pytest.approx(expected, rel=REL, abs=1e-4)


def test_a_weight_that_keeps_the_step_off_the_limit_holds_through_a_later_saturation(pid: ScanDriver) -> None:
    """b = 0 (AMIGO's) keeps the setpoint out of P: the step's first output is the integral's, and when the
    filtered setpoint later drives the output to the limit the weight still holds back the approach."""
    xs = [20.0] * 100 + [20.0 + 0.25 * k for k in range(1, 399)] + [119.5] * 50
    runs = {}
    for weight in (1.0, 0.0):
        configure(pid, kp=4.0, tn=20.0, tv=0.0, td=0.0, ymin=0.0, ymax=100.0, weight=weight)
        run(pid, 20.0, [20.0] * 3)
        runs[weight] = run(pid, 120.0, xs)
    assert runs[0.0][0] < 100.0 and max(runs[0.0]) == 100.0
    left = [k for k in range(1, len(xs)) if runs[0.0][k - 1] == 100.0 and runs[0.0][k] < 100.0]
    assert left and left[0] < next(k for k, y in enumerate(runs[1.0]) if y < 100.0)


def test_a_ramp_written_point_by_point_passes_the_weight_whole(pid: ScanDriver) -> None:
    """Changes up to fWeightMinStep per call move the filtered setpoint with W: a ramp meets the whole P
    part (through the filter it would trail by (1 - b) Tn times its rate), a larger change is a step."""
    ramp = [20.0 + 0.2 * k for k in range(1, 101)]
    runs = {}
    for weight in (1.0, 0.5):
        configure(pid, kp=2.0, tn=20.0, tv=0.0, td=0.0, weight=weight, weight_min_step=0.5)
        run(pid, 20.0, [20.0] * 3)
        runs[weight] = [run(pid, w, [20.0 + 0.2 * k])[0] for k, w in enumerate(ramp)]
    assert runs[0.5] == pytest.approx(runs[1.0], rel=REL, abs=1e-4)
    configure(pid, kp=2.0, tn=20.0, tv=0.0, td=0.0, weight=0.5, weight_min_step=0.5)
    y0 = run(pid, 20.0, [20.0] * 3)[-1]
    assert run(pid, 21.0, [20.0])[0] == pytest.approx(y0 + 2.0 * 0.5 * 1.0 + 2.0 * TS / 20.0 * 1.0, rel=REL)
