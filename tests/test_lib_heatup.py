"""Model-based setpoint response (FB_CtrlHeatUp inside FB_TempController, sParam.bHeatUp): on seed 003's
hot end (FOPDT K = 0.5916 degC/%, T = 23.4 s, L = 10.6 s) a 160 -> 200 degC step with AUTO's robust PID
set (AMIGO, Ms <= 1.6 on the model) settles within 1.05x the bang-hold bound with at most 0.5 % overshoot;
with the plant's T and L 30 % off the model (every combination) within 1.5x the true plant's bound and 2 %
overshoot, also at 0.2 degC sensor noise, with no false alarm of the heater monitor (the test requires
ACTIVE throughout). The reference path the PID follows has no step at the switch or at the end. It stays
fail-safe (IDLE and a sensor fault give 0 in the scan, also in the limit phase); without a usable model
it is the plain PID. On an oven of four equal lags, which TUNE identifies as such, the response plans on
that model and lands without the overshoot a first-order plan leaves there."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from modbus_bridge.plants.base import PlantDisturbance
from modbus_bridge.plants.lti import NLag
from modbus_bridge.plants.response import (
    PlantModel,
    bang_hold_bound,
    max_sensitivity,
    pid_frequency_response,
    sample_delay,
)
from tests.st_helpers import ScanDriver, controller_program, load_test_app
from tests.test_lib_tuner import RULE_AMIGO, Fopdt, rule_values

IDLE, ACTIVE = 0, 2
TS = 0.1
K, T, L = 0.5916, 23.4, 10.6  # seed 003 (scenario seed003_hotend_fuzzy), identified = true here
ROBUST_MS = 1.6  # the feedback part's robustness goal


# AUTO's rule at tau = L/(L+T) = 0.31, AMIGO, as documented: Kp, Tn, Tv, Td (the step size is CHR's only)
PID_SET = rule_values(RULE_AMIGO, ks=K, tu=L, tg=T, vmax=0.0, dy=100.0)
W0, W1 = 160.0, 200.0
STEP_AT, HORIZON = 60.0, 300.0
BAND = 0.02


@dataclass
class StepResult:
    settling_s: float
    overshoot_pct: float
    t: list[float]
    y: list[float]
    refs: list[tuple[bool, bool, float, float]]  # per scan: response active, limit phase, fWRef, X used


def controller(heat_up: bool, model=(K, T, L)) -> ScanDriver:
    drv = ScanDriver(load_test_app(controller_program()))
    kp, tn, tv, td = PID_SET
    for name, value in dict(fKp=kp, fTn=tn, fTv=tv, fTd=td, fYMin=0.0, fYMax=100.0, fWMax=300.0,
                            fXMax=400.0, fTempAbsHigh=300.0, fPvTimeout=0.0, fKs=model[0], fTg=model[1],
                            fTu=model[2]).items():
        drv.set(f"sPar.{name}", value)
    drv.set("sPar.bHeatUp", heat_up)
    return drv


def step_response(drv: ScanDriver, k: float = K, t: float = T, l: float = L,
                  noise: float = 0.03, w1: float = W1) -> StepResult:
    plant = Fopdt(k=k, t=t, l=l, x0=W0, dt=TS, noise=noise)  # 0.03: a live sensor's noise (frozen-PV check)
    drv.set("fbUut.fW1", W0)
    drv.set("nMode", ACTIVE)
    ts, ys, refs = [], [], []
    for n in range(round(HORIZON / TS)):
        if n == round(STEP_AT / TS):
            drv.set("fbUut.fW1", w1)
        drv.set("fbUut.fX", plant.measure())
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("nState") == ACTIVE, f"state {drv.get('nState')} at {n * TS:.1f} s"
        plant.step(drv.get("fbUut.fY"))
        if n >= round(STEP_AT / TS):
            ts.append(n * TS - STEP_AT)
            ys.append(plant.x)
            refs.append((drv.get("fbUut.fbHeatUp.bActive"), drv.get("fbUut.fbHeatUp.bLimitPhase"),
                         drv.get("fbUut.fbHeatUp.fWRef"), drv.get("fbUut.fXUsed")))
    outside = [tt for tt, y in zip(ts, ys, strict=True) if abs(y - w1) > BAND * abs(w1 - W0)]
    settling = outside[-1] + TS if outside else 0.0
    if outside and outside[-1] >= ts[-1] - TS:
        settling = math.inf
    direction = math.copysign(1.0, w1 - W0)
    overshoot = max(0.0, max((y - w1) * direction for y in ys)) / abs(w1 - W0) * 100.0
    return StepResult(settling, overshoot, ts, ys, refs)


def bound_s(k: float = K, t: float = T, l: float = L) -> float:
    pm = PlantModel("fopdt", dict(gain_c_per_pct=k, time_constant_s=t, dead_time_s=l, ambient_c=W0))
    return bang_hold_bound(pm, W0, W1, TS, 200.0).settling_s


def test_the_feedback_part_is_robust() -> None:
    omegas = np.logspace(-4, 1, 20000)
    kp, tn, tv, td = PID_SET
    loop = pid_frequency_response(kp, tn, tv, td, omegas) * K * sample_delay(omegas, L) \
        / (1j * omegas * T + 1.0)
    assert max_sensitivity(loop) <= ROBUST_MS


def test_seed003_step_within_the_bound_without_overshoot() -> None:
    bound = bound_s()
    with_model = step_response(controller(heat_up=True))
    plain = step_response(controller(heat_up=False))
    print(f"seed 003 160->200 degC: bound {bound:.1f} s; model-based {with_model.settling_s:.1f} s, "
          f"{with_model.overshoot_pct:.2f} %; PID alone {plain.settling_s:.1f} s, "
          f"{plain.overshoot_pct:.2f} %")
    assert with_model.settling_s <= 1.05 * bound
    assert with_model.overshoot_pct <= 0.5
    assert with_model.settling_s < plain.settling_s


def test_a_cool_down_mirrors_the_heat_up() -> None:
    """Split range (fYMin -100 %) with the same set for cooling: 160 -> 120 degC runs the cooling limit,
    then the holding power; on this linear plant the mirror of the heating step, so the same bound."""
    drv = controller(heat_up=True)
    kp, tn, tv, td = PID_SET
    for name, value in dict(fYMin=-100.0, fKpCool=kp, fTnCool=tn, fTvCool=tv, fTdCool=td,
                            fTempAbsLow=-100.0).items():
        drv.set(f"sPar.{name}", value)
    res = step_response(drv, w1=2.0 * W0 - W1)
    bound = bound_s()
    print(f"cool-down 160->120 degC: {res.settling_s:.1f} s (mirror bound {bound:.1f} s), "
          f"{res.overshoot_pct:.2f} %")
    assert res.settling_s <= 1.05 * bound
    assert res.overshoot_pct <= 0.5


def test_without_a_usable_model_it_is_the_plain_pid() -> None:
    plain = step_response(controller(heat_up=False))
    no_model = step_response(controller(heat_up=True, model=(0.0, 0.0, 0.0)))
    assert no_model.y == plain.y


def limit_phase(drv: ScanDriver) -> None:
    drv.set("fbUut.fW1", W0)
    drv.set("nMode", ACTIVE)
    for n in range(50):
        drv.set("fbUut.fX", W0 + 0.01 * (n % 3))
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
    drv.set("fbUut.fW1", W1)
    drv.scan(5)
    assert drv.get("fbUut.fbHeatUp.bLimitPhase") and drv.get("fbUut.fY") == 100.0, "not at the output limit"


@pytest.mark.parametrize("fault", ["idle", "sensor short"])
def test_idle_or_a_fault_during_the_limit_phase_gives_zero_in_the_same_scan(fault: str) -> None:
    drv = controller(heat_up=True)
    limit_phase(drv)
    if fault == "idle":
        drv.set("nMode", IDLE)
    else:
        drv.set("fbUut.bSensorShort", True)
    drv.scan()
    assert drv.get("fbUut.fY") == 0.0 and not drv.get("fbUut.bYPWMPos")


@pytest.mark.parametrize("model", [(math.nan, T, L), (K, math.inf, L), (K, T, -1.0), (-K, T, L), (K, 0.0, L)])
def test_an_unusable_model_starts_no_response(model) -> None:
    drv = controller(heat_up=True, model=model)
    with pytest.raises(AssertionError, match="not at the output limit"):
        limit_phase(drv)
    assert not drv.get("fbUut.fbHeatUp.bActive")
    assert math.isfinite(drv.get("fbUut.fY"))


MISMATCH = [(0.7, 1.0), (1.3, 1.0), (1.0, 0.7), (1.0, 1.3), (0.7, 1.3), (1.3, 0.7), (0.7, 0.7), (1.3, 1.3)]
# Fopdt's noise is uniform: +-0.35 degC is 0.2 degC standard deviation, the level of the noise goals
NOISY = 0.2 * math.sqrt(3.0)
MISMATCH_OVERSHOOT_PCT, MISMATCH_BOUND_RATIO = 2.0, 1.5


def _within_goals(t_scale: float, l_scale: float, noise: float) -> None:
    t, l = T * t_scale, L * l_scale
    res = step_response(controller(heat_up=True), t=t, l=l, noise=noise)
    bound = bound_s(t=t, l=l)
    print(f"T x{t_scale} L x{l_scale}, noise +-{noise:.2f} degC: {res.settling_s:.1f} s "
          f"(bound {bound:.1f} s, {res.settling_s / bound:.2f}x), {res.overshoot_pct:.2f} %")
    assert res.overshoot_pct <= MISMATCH_OVERSHOOT_PCT
    assert res.settling_s <= MISMATCH_BOUND_RATIO * bound


@pytest.mark.parametrize(("t_scale", "l_scale"), MISMATCH, ids=[f"T{t}-L{l}" for t, l in MISMATCH])
def test_model_mismatch_within_goals(t_scale: float, l_scale: float) -> None:
    _within_goals(t_scale, l_scale, 0.03)


@pytest.mark.parametrize(("t_scale", "l_scale"), [(0.7, 1.3), (1.3, 1.3)], ids=["T0.7-L1.3", "T1.3-L1.3"])
def test_model_mismatch_within_goals_with_sensor_noise(t_scale: float, l_scale: float) -> None:
    _within_goals(t_scale, l_scale, NOISY)


@pytest.mark.parametrize(("t_scale", "l_scale"), [(1.0, 1.0), (0.7, 1.3), (1.3, 0.7)])
def test_the_reference_path_has_no_step(t_scale: float, l_scale: float) -> None:
    """At the switch the path starts at the measured X; it reaches W before the response ends; between
    scans it moves no more than the plant can (its limit-step slope K * 100 % / T)."""
    res = step_response(controller(heat_up=True), t=T * t_scale, l=L * l_scale)
    active = [r for r in res.refs if r[0]]
    after = [r for r in active if not r[1]]
    assert active and after, "no response ran"
    first = after[0]
    assert first[2] == pytest.approx(first[3], abs=1e-4), "the path does not start at the measured X"
    assert after[-1][2] == pytest.approx(W1, abs=1e-3), "the path has not reached W when the response ends"
    max_move = K * 100.0 / (T * 0.7) * TS
    steps = [abs(b[2] - a[2]) for a, b in zip(after, after[1:], strict=False)]
    assert max(steps) <= max_move, f"path step {max(steps):.3f} degC in one scan"


MANUAL, TUNE = 4, 5
TUNE_READY = 4
MOVING_SEEN_TOLERANCE = 0.10  # the plant's L and T as the limit phase saw it, against the true plant
MOVING_OVERSHOOT_PCT = 5.0  # of the step; a plant at rest is held to 0.5 %, one still moving carries more


@dataclass
class HandOver:
    seen: tuple[float, float] | None  # L, T the limit phase saw, when one ended
    xs: list[float]  # plant temperature from the hand-over on
    started: bool  # a response ran
    state: int  # controller state at the end


def hand_over(pre_s: float, y_pre: float, w: float, after_s: float = HORIZON) -> HandOver:
    """MANUAL at y_pre for pre_s (a plant still moving when TUNE hands over), then ACTIVE towards w."""
    drv = controller(heat_up=True)
    plant = Fopdt(k=K, t=T, l=L, x0=W0, dt=TS, noise=0.03)
    drv.set("fbUut.fYManual", y_pre)
    drv.set("fbUut.fW1", w)
    drv.set("nMode", MANUAL)
    out, limit_before = HandOver(None, [], False, 0), False
    for n in range(round((pre_s + after_s) / TS)):
        if n == round(pre_s / TS):
            drv.set("nMode", ACTIVE)
        drv.set("fbUut.fX", plant.measure())
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        plant.step(drv.get("fbUut.fY"))
        out.started = out.started or drv.get("fbUut.fbHeatUp.bActive")
        limit = drv.get("fbUut.fbHeatUp.bLimitPhase")
        if limit_before and not limit:
            out.seen = (drv.get("fbUut.fbHeatUp.fTuSeen"), drv.get("fbUut.fbHeatUp.fTgSeen"))
        limit_before = limit
        if n >= round(pre_s / TS):
            out.xs.append(plant.x)
    out.state = drv.get("nState")
    return out


@pytest.mark.parametrize(
    ("pre_s", "y_pre", "w"),
    [(40.0, 60.0, 175.0), (85.0, 60.0, 175.0), (20.0, 30.0, W1), (40.0, 30.0, W1)],
    ids=["cool-40s-into-a-rise", "cool-85s-into-a-rise", "heat-20s-into-a-rise", "heat-40s-into-a-rise"],
)
def test_a_response_started_on_a_moving_plant_sees_the_plant(pre_s: float, y_pre: float, w: float) -> None:
    """TUNE hands over with the hot end still rising, so a response may start on a plant that moves on its
    own. That motion goes on for a dead time; taken off X, the limit phase sees the plant's L and T within
    10 % and the response stays within 5 % of the step (before: L seen 0.3-5.7 s for 10.6 s, 15-37 %)."""
    run = hand_over(pre_s, y_pre, w)
    seen, xs = run.seen, run.xs
    assert run.state == ACTIVE
    assert seen is not None, "no response ran"
    assert seen[0] == pytest.approx(L, rel=MOVING_SEEN_TOLERANCE), f"dead time seen {seen[0]:.2f} s"
    assert seen[1] == pytest.approx(T, rel=MOVING_SEEN_TOLERANCE), f"time constant seen {seen[1]:.2f} s"
    step = abs(w - xs[0])
    beyond = max((x - w) * math.copysign(1.0, w - xs[0]) for x in xs)
    assert 100.0 * beyond / step <= MOVING_OVERSHOOT_PCT, f"{100.0 * beyond / step:.1f} % past W"
    assert abs(xs[-1] - w) <= BAND * step


def test_a_holding_power_at_the_limit_starts_no_response() -> None:
    """Down to 0.5 degC above the plant's ambient the holding power is 0.8 %, next to the 0 % limit: the
    model's limit phase would last 4.2 T and its switch would wait on a rise that hardly moves. The PID
    takes it (no response, no held integrator); the response still runs for a target 5 degC higher."""
    for w, expected in ((W0 + 0.5, False), (W0 + 5.0, True)):
        run = hand_over(200.0, 60.0, w, after_s=200.0)
        assert run.started is expected, f"W {w}: response {'ran' if run.started else 'did not run'}"
        assert run.state == ACTIVE


# the bench oven of scenario nlag_oven: 2.2 e^(-4 s) / (45 s + 1)^4 (its 3 s delay and 1 s sensor lag)
OVEN_K, OVEN_T, OVEN_N, OVEN_L = 2.2, 45.0, 4, 4.0
OVEN_AMBIENT, OVEN_W0, OVEN_W1 = 25.0, 100.0, 150.0
OVEN_TS, OVEN_REST_S, OVEN_HORIZON_S = 0.2, 2000.0, 1200.0
OVEN_SUPERVISION = dict(fWatchPeriod=240.0, fRunawayPeriod=300.0)  # the scenario's, as for a slow bed
OVEN_Y_TUNE = 60.0  # TUNE's step, %


def oven_unit_step(x):
    """The unit step response of the oven's four equal lags at x = (t - L) / T (0 before the delay)."""
    x = np.clip(x, 0.0, None)
    return 1.0 - np.exp(-x) * sum(x**k / math.factorial(k) for k in range(OVEN_N))


def oven_two_point() -> tuple[float, float]:
    """(Tu, Tg) of the two-point FOPDT (seed 003, Smith) of the oven's step response: what TUNE reports."""
    from scipy.optimize import brentq

    x28, x63 = (brentq(lambda x, lv=level: float(oven_unit_step(x)) - lv, 0.0, 10.0 * OVEN_N)
                for level in (0.283, 0.632))
    tg = 1.5 * (x63 - x28) * OVEN_T
    return OVEN_L + x63 * OVEN_T - tg, tg


def oven_loop(heat_up: bool, model: tuple[float, float, float], l_scale: float = 1.0,
              initial_c: float | None = None, t_scale: float = 1.0,
              k_scale: float = 1.0) -> tuple[ScanDriver, NLag, PlantDisturbance]:
    """The controller on the oven's cycle and supervision times, and the oven (delay times l_scale, lags
    times t_scale, gain times k_scale)."""
    drv = controller(heat_up=heat_up, model=model)
    for name, value in dict(fTaskCycleTime=OVEN_TS, fCtrlCycleTime=OVEN_TS, **OVEN_SUPERVISION).items():
        drv.set(f"sPar.{name}", value)
    plant = NLag(gain_c_per_pct=OVEN_K * k_scale, time_constant_s=OVEN_T * t_scale, order=float(OVEN_N),
                 dead_time_s=OVEN_L * l_scale, ambient_c=OVEN_AMBIENT, initial_c=initial_c)
    return drv, plant, PlantDisturbance.for_channels(1)


def oven_tuned(order: int, initial_c: float, l_scale: float = 1.0, t_scale: float = 1.0,
               k_scale: float = 1.0) -> tuple[ScanDriver, NLag, PlantDisturbance]:
    """oven_loop with the heat-up, the oven's two-point FOPDT as the model (of this order) and AMIGO's set."""
    tu, tg = oven_two_point()
    drv, plant, dist = oven_loop(True, (OVEN_K, tg, tu), l_scale, initial_c=initial_c, t_scale=t_scale,
                                 k_scale=k_scale)
    kp, tn, tv, td = rule_values(RULE_AMIGO, ks=OVEN_K, tu=tu, tg=tg, vmax=0.0, dy=100.0)
    for name, value in dict(fKp=kp, fTn=tn, fTv=tv, fTd=td, nTuneOrder=order).items():
        drv.set(f"sPar.{name}", value)
    return drv, plant, dist


def tune_from(drv: ScanDriver, plant, dist: PlantDisturbance, ts: float, w: float, timeout_s: float,
              noise: float, rng: np.random.Generator) -> None:
    """TUNE towards w on a plant in the loop (its PV with this noise) until READY, then ACTIVE."""
    drv.set("sPar.fTuneTimeout", timeout_s)
    drv.set("fbUut.fW1", w)
    drv.set("nMode", TUNE)
    seq = 0
    while drv.get("nTuneState") != TUNE_READY:
        assert seq * ts < timeout_s, "TUNE did not end"
        seq += 1
        drv.set("fbUut.fX", plant.temperatures()[0] + rng.normal(0.0, noise))
        drv.set("fbUut.nPvSequence", seq)
        drv.scan()
        plant.step([drv.get("fbUut.fY")], ts, dist)
    drv.set("nMode", ACTIVE)


def step_from_rest(drv: ScanDriver, plant, dist: PlantDisturbance, ts: float, rest_s: float, horizon_s: float,
                   w0: float, w1: float, noise: float, seed: int,
                   sensor: Callable[[float], float] = float) -> StepResult:
    """W0 for rest_s, then W1 for horizon_s, ACTIVE throughout, on a plant in the loop (its PV with this
    noise, then read through `sensor`, e.g. an ADC's counts: a live sensor passes the frozen-PV check): the
    true temperature's 2 % settling and overshoot of the step (heating)."""
    rng = np.random.default_rng(seed)
    drv.set("fbUut.fW1", w0)
    drv.set("nMode", ACTIVE)
    t_s, xs = [], []
    start = round(rest_s / ts)
    for n in range(start + round(horizon_s / ts)):
        if n == start:
            drv.set("fbUut.fW1", w1)
        x = plant.temperatures()[0]
        drv.set("fbUut.fX", sensor(x + rng.normal(0.0, noise)))
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("nState") == ACTIVE, f"state {drv.get('nState')} at {n * ts:.1f} s"
        if n >= start:
            t_s.append((n - start) * ts)
            xs.append(x)
        plant.step([drv.get("fbUut.fY")], ts, dist)
    return step_figures(t_s, xs, w0, w1, ts)


def step_figures(t_s: list[float], xs: list[float], w0: float, w1: float, ts: float) -> StepResult:
    """2 % settling (from the first sample, s) and overshoot (% of the step) of a heating step w0 -> w1."""
    step = w1 - w0
    outside = [t for t, x in zip(t_s, xs, strict=True) if abs(x - w1) > BAND * step]
    settling = outside[-1] + ts if outside else 0.0
    return StepResult(settling, max(0.0, max(xs) - w1) / step * 100.0, t_s, xs, [])


def oven_step(order: int, l_scale: float = 1.0, t_scale: float = 1.0, k_scale: float = 1.0) -> StepResult:
    """100 -> 150 degC on the oven with AMIGO's set for its two-point FOPDT, the model of this order."""
    drv, plant, dist = oven_tuned(order, OVEN_W0, l_scale, t_scale, k_scale)
    return step_from_rest(drv, plant, dist, OVEN_TS, OVEN_REST_S, OVEN_HORIZON_S, OVEN_W0, OVEN_W1,
                          noise=0.03, seed=4)


def oven_bound(t_scale: float = 1.0, k_scale: float = 1.0) -> float:
    pm = PlantModel("nlag", dict(gain_c_per_pct=OVEN_K * k_scale, time_constant_s=OVEN_T * t_scale,
                                 order=float(OVEN_N),
                                 dead_time_s=OVEN_L, ambient_c=OVEN_AMBIENT))
    return bang_hold_bound(pm, OVEN_W0, OVEN_W1, OVEN_TS, 600.0).settling_s


# the bang-hold bound may overshoot (1.9 % here); the plan keeps within 0.25 % (one switch planned so: 1.19x)
OVEN_BOUND_RATIO = 1.1


def test_an_oven_of_equal_lags_lands_on_its_n_lag_model() -> None:
    """One switch from the limit to the holding power lands a first-order lag on W; a chain of four lags
    still rises from the pulse it holds: planned on the first-order model the oven overshoots like the PID
    alone. Planned on the four lags, the pulse is longer than one that lands the chain on its own, and the
    second plan, made where the rise has shown the plant, brakes what the chain holds beyond W: the model's
    response stays within 0.25 % of the step both ways."""
    bound = oven_bound()
    fopdt_plan, nlag_plan = oven_step(order=1), oven_step(order=OVEN_N)
    print(f"oven 100->150 degC: bound {bound:.1f} s; planned on 4 lags {nlag_plan.settling_s:.1f} s, "
          f"{nlag_plan.overshoot_pct:.2f} %; on the first-order model {fopdt_plan.settling_s:.1f} s, "
          f"{fopdt_plan.overshoot_pct:.2f} %")
    assert nlag_plan.overshoot_pct <= 0.5
    assert nlag_plan.settling_s <= OVEN_BOUND_RATIO * bound
    assert fopdt_plan.overshoot_pct > 5.0 and fopdt_plan.settling_s > 2.0 * bound


@pytest.mark.parametrize("l_scale", [0.7, 1.3])
def test_an_oven_with_another_delay_stays_within_the_mismatch_goals(l_scale: float) -> None:
    res = oven_step(order=OVEN_N, l_scale=l_scale)
    print(f"oven, delay x{l_scale}: {res.settling_s:.1f} s, {res.overshoot_pct:.2f} %")
    assert res.overshoot_pct <= 2.0
    assert res.settling_s <= 1.5 * oven_bound()


@dataclass
class TuneHandOver:
    order: int
    peak_c: float
    low_after_peak_c: float
    unavoidable_peak_c: float  # the true oven's peak with the output at 0 % from the hand-over on
    monitor_loss: list[float]  # the heater monitor's apparent loss, %, per scan after the hand-over


def oven_tune_hand_over(heat_up: bool, after_s: float = 900.0, t_scale: float = 1.0) -> TuneHandOver:
    """TUNE the oven from ambient towards 100 degC (60 % step, AUTO), then ACTIVE at once; from then on the
    oven's lags are t_scale times what TUNE saw."""
    drv, plant, dist = oven_loop(heat_up, (0.0, 0.0, 0.0))
    drv.set("sPar.fYTune", OVEN_Y_TUNE)
    drv.set("sPar.fTuneTimeout", 3000.0)
    drv.set("nRule", 0)
    rng = np.random.default_rng(5)
    drv.set("fbUut.fW1", OVEN_W0)
    drv.set("nMode", TUNE)
    xs: list[float] = []
    losses: list[float] = []
    n = 0
    while n < round((3000.0 + after_s) / OVEN_TS) and len(xs) < round(after_s / OVEN_TS):
        drv.set("fbUut.fX", plant.temperatures()[0] + rng.normal(0.0, 0.03))
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        if drv.get("nMode") == TUNE and drv.get("nTuneState") == TUNE_READY:
            drv.set("nMode", ACTIVE)
            age, x0 = drv.get("fbUut.fbTuner.fStepAge"), drv.get("fbUut.fbTuner.fX0")
            plant.time_constant_scale = t_scale
        plant.step([drv.get("fbUut.fY")], OVEN_TS, dist)
        if drv.get("nMode") == ACTIVE:
            # the scan that ended TUNE still reports TUNED; ACTIVE from the next on
            assert not xs or drv.get("nState") == ACTIVE, \
                f"state {drv.get('nState')} at {n * OVEN_TS:.1f} s, alarm {drv.get('fbUut.dwAlarm'):#x}"
            xs.append(plant.temperatures()[0])
            losses.append(drv.get("fbUut.fbMonitor.fLoss"))
        n += 1
    assert xs, "TUNE did not end"
    # the true oven's response to the tune step cut to 0 % at the hand-over: the least peak any output gives
    t = np.arange(0.0, 2000.0, OVEN_TS)
    cut = x0 + OVEN_K * OVEN_Y_TUNE * (oven_unit_step((t + age - OVEN_L) / OVEN_T)
                                      - oven_unit_step((t - OVEN_L) / OVEN_T))
    top = int(np.argmax(xs))
    return TuneHandOver(drv.get("sPar.nTuneOrder"), max(xs), min(xs[top:]), float(cut.max()), losses)


def test_a_tune_hand_over_on_the_oven_brakes_the_heat_its_lags_hold() -> None:
    """TUNE's step ends at 80 % of the way to W, and the oven's four lags still hold the heat of 60 %: even
    0 % from then on leaves it well past W. With the heat-up the hand-over plans on the identified lags and
    the step's known history (0 % for a while, then the holding power): its peak stays near that least peak
    and it comes back to W without undershoot; the PID alone, bumpless from the step's 60 %, goes far
    higher."""
    planned, plain = oven_tune_hand_over(heat_up=True), oven_tune_hand_over(heat_up=False)
    least = planned.unavoidable_peak_c - OVEN_W0
    print(f"oven TUNE -> 100 degC: least peak {planned.unavoidable_peak_c:.1f} degC; planned "
          f"{planned.peak_c:.1f} degC, then down to {planned.low_after_peak_c:.2f}; "
          f"PID alone {plain.peak_c:.1f}")
    assert planned.order == OVEN_N
    assert planned.peak_c - OVEN_W0 <= 1.25 * least
    assert planned.low_after_peak_c >= OVEN_W0 - BAND * (OVEN_W0 - OVEN_AMBIENT)
    assert plain.peak_c - OVEN_W0 >= 1.5 * least


MONITOR_SETTLED_LOSS_PCT = 5.0  # a quarter of the open/weak check's least threshold (fMonitorLossMin 20 %)


@pytest.mark.parametrize("t_scale", [1.0, 1.3])
def test_the_heater_monitor_starts_from_the_rest_before_a_tune_step_on_a_lag_chain(t_scale: float) -> None:
    """After the hand-over's brake the oven's X stands near its peak while the four lags still hold the tune
    step's heat: read as a first-order plant at rest, that would be an offset of about 80 degC and, once
    the chain has settled, a permanent apparent loss of a quarter of the output, next to the open-heater
    threshold (past it with the oven 30 % slower than TUNE saw). The monitor takes the offset from the rest
    before the step instead; no alarm, and once settled the loss it sees is small."""
    run = oven_tune_hand_over(heat_up=True, after_s=1200.0, t_scale=t_scale)
    settled = run.monitor_loss[-round(300.0 / OVEN_TS):]
    print(f"oven TUNE -> 100 degC, lags x{t_scale}: apparent loss over the last 300 s "
          f"{min(settled):.1f} .. {max(settled):.1f} %")
    assert max(abs(v) for v in settled) <= MONITOR_SETTLED_LOSS_PCT


def test_a_heat_up_as_the_loop_starts_raises_no_monitor_alarm() -> None:
    """ACTIVE from the first scan, the oven at rest 50 degC below W: the monitor's model starts a dead time
    and two filter times later, when the heat-up's pulse is already in the four lags, where X does not show
    it. Taken as a first-order plant at rest there, its offset made the rest of the pulse look like heat
    nobody commanded (stuck-on at 145 s); it takes the offset from the rest the response started at."""
    drv, plant, dist = oven_tuned(OVEN_N, OVEN_W0)
    rng = np.random.default_rng(6)
    drv.set("fbUut.fW1", OVEN_W1)
    drv.set("nMode", ACTIVE)
    xs = []
    for n in range(round(OVEN_HORIZON_S / OVEN_TS)):
        drv.set("fbUut.fX", plant.temperatures()[0] + rng.normal(0.0, 0.03))
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("fbUut.dwAlarm") == 0, f"alarm {drv.get('fbUut.dwAlarm'):#x} at {n * OVEN_TS:.1f} s"
        xs.append(plant.temperatures()[0])
        plant.step([drv.get("fbUut.fY")], OVEN_TS, dist)
    outside = [i for i, x in enumerate(xs) if abs(x - OVEN_W1) > BAND * (OVEN_W1 - OVEN_W0)]
    settling, overshoot = (outside[-1] + 1) * OVEN_TS, (max(xs) - OVEN_W1) / (OVEN_W1 - OVEN_W0) * 100.0
    print(f"oven, ACTIVE from the first scan, 100 -> 150 degC: {settling:.1f} s, {overshoot:.2f} %, no alarm")
    assert overshoot <= 0.5
    assert settling <= OVEN_BOUND_RATIO * oven_bound()


T1_K, T1_T, T1_L, T1_W, T1_AMBIENT, T1_Y_TUNE = 3.4, 140.0, 5.5, 200.0, 25.0, 60.0  # RepRapFirmware's hot end


def t1_tune_hand_over(heat_up: bool, after_s: float = 400.0) -> tuple[float, float, float]:
    """TUNE T1's hot end from ambient towards 200 degC (60 % step, AUTO), then ACTIVE at once: X at the
    hand-over, the peak after it and the 2 % settling time of the rest of the way to W."""
    drv = controller(heat_up)
    drv.set("sPar.fYTune", T1_Y_TUNE)
    drv.set("sPar.fTuneTimeout", 3000.0)
    drv.set("nRule", 0)
    plant = Fopdt(k=T1_K, t=T1_T, l=T1_L, x0=T1_AMBIENT, dt=TS, noise=0.03)
    drv.set("fbUut.fW1", T1_W)
    drv.set("nMode", TUNE)
    xs: list[float] = []
    for n in range(round((3000.0 + after_s) / TS)):
        drv.set("fbUut.fX", plant.measure())
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        if drv.get("nMode") == TUNE and drv.get("nTuneState") == TUNE_READY:
            drv.set("nMode", ACTIVE)
        plant.step(drv.get("fbUut.fY"))
        if drv.get("nMode") == ACTIVE:
            xs.append(plant.x)
            if len(xs) >= round(after_s / TS):
                break
    assert xs, "TUNE did not end"
    band = BAND * (T1_W - xs[0])
    outside = [i for i, x in enumerate(xs) if abs(x - T1_W) > band]
    settling = (outside[-1] + 1) * TS if outside else 0.0
    return xs[0], max(xs), settling


def test_a_tune_hand_over_on_a_first_order_hot_end_lands_on_w() -> None:
    """TUNE's step ends at 80 % of the way to W with the hot end still rising on 60 %; the heat-up plans the
    rest on the step's known history (a first-order model, as on the n-lag oven): it reaches W without
    overshoot well before the PID alone, which creeps in on its integrator. Planned on the slope seen after
    the hand-over instead, the response went past W and took twice as long."""
    x_ho, peak, settling = t1_tune_hand_over(heat_up=True)
    _, plain_peak, plain_settling = t1_tune_hand_over(heat_up=False)
    print(f"T1 TUNE -> {T1_W:g} degC from {x_ho:.1f}: planned peak {peak:.2f}, 2 % settling "
          f"{settling:.1f} s; PID alone {plain_peak:.2f}, {plain_settling:.1f} s")
    assert peak - T1_W <= BAND * (T1_W - x_ho)
    assert settling < 0.5 * plain_settling
