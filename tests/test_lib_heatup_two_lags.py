"""Model-based setpoint response planned on two unequal lags (a TCLab-like heater: block 16.7 s behind its
heater, sensor 140 s behind the block) over the library's FB_TempController on the soft-PLC. The model is
the one TUNE publishes for such a plant: nTuneOrder 2, fTuneLagRatio = rho and the two-point FOPDT of the
two lags; the PID is AMIGO's on that FOPDT. A step from rest lands within the goals, sooner than one
switch can: a longer pulse, then a brake at the other limit (one switch landed the nominal step at 1.09 x
the bound; the bound, one switch too, overshoots 2 % to enter the band early). A plant whose rise clearly
differs from the model's gets its pulse planned again on the lags the rise shows (its slope the slow lag,
its level the fast one). A faster rise (a faster sensor, a stronger heater: the slope cannot tell them
apart) is planned on the lag seen, with a brake half the way to the longest it allows (without the new
plan, a sensor 30 % faster overshot 16.5 %; with the brake as far as the model's, 2.85 %), the slow lag the
shortest within a standard error of the line's slope and level, with the fast lag read with it (read as it
came out, 4 of 7 noise draws of both lags 30 % shorter overshot past 2 %, and 1 of 7 of a sensor 30 %
faster); a slower one (a
slower sensor, a weaker heater) halfway to it, on the square root of its scale (planned on the model's
lags, a sensor 30 % slower overshot 2.75 %; on the lag seen, a 20 % weaker heater stalled below W, 1.62 x
the bound; with a brake, that heater took 1.51 x), with one switch. The PID follows the path, its
integrator resting while the path is farther from W than the settling band (a plant that lags the path
would otherwise wind it up), unless X runs ahead of the path (a stronger heater: its integral takes off
the power it does not need). The figures of the cases that miss the goals are expected failures that state
them. A brake is timed on the fast lag: when the line's level shows it clearly off the model's, the brake
is planned again on it.
At the TCLab's 0.2 degC noise one run's overshoot moves by a few tenths of a percent with the noise draw
(0.075 degC is 0.5 % of the step), so the nominal step is held to the goals on the mean of NOMINAL_SEEDS
noise draws, and the worst of them is printed.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pytest

from modbus_bridge.plants.base import PlantDisturbance
from modbus_bridge.plants.lti import TransferFunctionPlant
from modbus_bridge.plants.response import PlantModel, bang_hold_bound
from tests.slow_cases import skip_unless_slow
from tests.test_lib_heatup import controller, step_from_rest
from tests.test_lib_tuner import RULE_AMIGO, rule_values, two_lags_two_point

K, T_SENSOR, T_BLOCK = 0.6, 140.0, 16.7  # degC/%, s, s
AMBIENT, W0, W1 = 21.0, 45.0, 60.0
TS, REST_S, HORIZON_S = 0.1, 1500.0, 700.0
NOISE = 0.2  # degC, the TCLab's
SUPERVISION = dict(fWatchPeriod=45.0, fTuneNoisePp=4.0 * NOISE)  # the application's zone-1 watch period
OVERSHOOT_GOAL = 0.5
BOUND_RATIO_GOAL = 1.05
MISMATCH_OVERSHOOT_GOAL, MISMATCH_BOUND_RATIO_GOAL = 2.0, 1.5
MISMATCH_SEED = 7
# a 20 % stronger heater over NOMINAL_SEEDS: planned on the slow lag as read, mean 3.98 %, worst 6.53 %
STRONGER_HEATER_MEAN_MAX, STRONGER_HEATER_WORST_MAX = 3.5, 4.0
NOMINAL_SEEDS = range(1, 8)
FAST_BLOCK_SEEDS = (1, 2)
FASTER_RISES = {"sensor x0.7": dict(sensor=0.7), "both x0.7": dict(sensor=0.7, block=0.7)}


def plant_params(sensor: float = 1.0, block: float = 1.0, gain: float = 1.0) -> dict:
    t1, t2 = T_SENSOR * sensor, T_BLOCK * block
    return dict(num=(K * gain,), den=(t1 * t2, t1 + t2, 1.0), ambient_c=AMBIENT)


@dataclass
class Step:
    settling_s: float
    overshoot_pct: float
    bound_s: float
    read: tuple[float, float]  # the slow and fast lag the rise's line read, over the model's (0: none)
    planned: float  # the slow lag planned on, over the model's
    seen: tuple[float, float]  # the plant published: Tu, Tg of the two-point FOPDT (s)


@functools.cache
def step(sensor: float = 1.0, block: float = 1.0, gain: float = 1.0, seed: int = MISMATCH_SEED) -> Step:
    """45 -> 60 degC from rest on the plant (lags and gain times these), the model being the nominal one."""
    tu, tg = two_lags_two_point(T_SENSOR, T_BLOCK)
    drv = controller(True, model=(K, tg, tu))
    kp, tn, tv, td = rule_values(RULE_AMIGO, ks=K, tu=tu, tg=tg, vmax=0.0, dy=100.0)
    for name, value in dict(fTaskCycleTime=TS, fCtrlCycleTime=TS, fKp=kp, fTn=tn, fTv=tv, fTd=td,
                            nTuneOrder=2, fTuneLagRatio=T_BLOCK / T_SENSOR, **SUPERVISION).items():
        drv.set(f"sPar.{name}", value)
    params = plant_params(sensor, block, gain)
    plant, dist = TransferFunctionPlant(**params), PlantDisturbance.for_channels(1)
    got = step_from_rest(drv, plant, dist, TS, REST_S, HORIZON_S, W0, W1, NOISE, seed=seed)
    bound = bang_hold_bound(PlantModel("transfer_function", params), W0, W1, TS, HORIZON_S).settling_s
    hu = "fbUut.fbHeatUp."
    return Step(got.settling_s, got.overshoot_pct, bound,
                (drv.get(hu + "fLagScale"), drv.get(hu + "fFastScale")), drv.get(hu + "fLagPlanScale"),
                (drv.get(hu + "fTuSeen"), drv.get(hu + "fTgSeen")))


def test_two_unequal_lags_land_on_their_model() -> None:
    runs = [step(seed=seed) for seed in NOMINAL_SEEDS]
    overshoot = float(np.mean([r.overshoot_pct for r in runs]))
    ratio = float(np.mean([r.settling_s / r.bound_s for r in runs]))
    worst_ratio = max(r.settling_s / r.bound_s for r in runs)
    print(f"two lags 140 s / 16.7 s, {len(runs)} noise draws: mean settling {ratio:.2f} x the bound "
          f"{runs[0].bound_s:.1f} s (worst {worst_ratio:.2f} x), mean overshoot {overshoot:.2f} % "
          f"(worst {max(r.overshoot_pct for r in runs):.2f} %)")
    assert overshoot <= OVERSHOOT_GOAL
    assert ratio <= BOUND_RATIO_GOAL


MISMATCH_SHORTFALLS = {
    "gain x1.2": "the rise reads as a slow lag 23 % shorter (planned on 32 %, within the line's errors), "
                 "so the pulse ends early, and the model's holding power then carries the stronger heater "
                 "past W before its integral has taken that power off: 2.65 %, 2.36 x",
}


def _mismatch_cases():
    for label, kw in (("sensor x0.7", dict(sensor=0.7)), ("sensor x1.3", dict(sensor=1.3)),
                      ("block x0.7", dict(block=0.7)), ("block x1.3", dict(block=1.3)),
                      ("gain x0.8", dict(gain=0.8)), ("gain x1.2", dict(gain=1.2)),
                      ("both x0.7", dict(sensor=0.7, block=0.7)), ("both x1.3", dict(sensor=1.3, block=1.3))):
        why = MISMATCH_SHORTFALLS.get(label)
        marks = [pytest.mark.xfail(reason=f"known shortfall: {why}", strict=True)] if why else []
        yield pytest.param(kw, marks=marks, id=label.replace(" ", "_"))


@pytest.mark.parametrize("mismatch", list(_mismatch_cases()))
def test_two_lags_unlike_their_model_stay_within_the_mismatch_goals(mismatch: dict) -> None:
    got = step(**mismatch)
    print(f"{mismatch}: settling {got.settling_s:.1f} s = {got.settling_s / got.bound_s:.2f} x the bound "
          f"{got.bound_s:.1f} s, overshoot {got.overshoot_pct:.2f} %")
    assert got.overshoot_pct <= MISMATCH_OVERSHOOT_GOAL
    assert got.settling_s <= MISMATCH_BOUND_RATIO_GOAL * got.bound_s


@pytest.mark.parametrize("label", list(FASTER_RISES))
def test_a_faster_rise_stays_within_the_mismatch_goals_over_noise_draws(label: str) -> None:
    """The lags read from a faster rise scatter with the noise (the level's error reaches the slow lag through
    the fast one); planned on the shortest slow lag within a standard error, every draw lands within the
    mismatch goals, where the lags as read carried 5 of 14 draws past 2 %. CI runs MISMATCH_SEED's draw in
    the mismatch test above."""
    skip_unless_slow(f"{label} over noise draws")
    runs = [step(**FASTER_RISES[label], seed=seed) for seed in NOMINAL_SEEDS]
    figures = ", ".join(f"{r.settling_s / r.bound_s:.2f} x / {r.overshoot_pct:.2f} %" for r in runs)
    print(f"{label}, noise draws {NOMINAL_SEEDS.start}-{NOMINAL_SEEDS.stop - 1}: {figures}")
    assert max(r.overshoot_pct for r in runs) <= MISMATCH_OVERSHOOT_GOAL
    assert max(r.settling_s / r.bound_s for r in runs) <= MISMATCH_BOUND_RATIO_GOAL


@pytest.mark.parametrize("sensor", [0.7, 1.3])
def test_the_plant_published_is_the_one_the_line_read_not_the_one_planned_on(sensor: float) -> None:
    """A faster rise is planned on a slow lag below the one read, a slower one between the read and the
    model's; the plant the response publishes (fHeatUpTuSeen, fHeatUpTgSeen) is the two-point FOPDT of the
    lags read."""
    got = step(sensor=sensor)
    slow, fast = got.read
    tu, tg = two_lags_two_point(slow * T_SENSOR, fast * T_BLOCK)
    print(f"sensor x{sensor}: read slow x{slow:.3f}, fast x{fast:.3f}, planned slow x{got.planned:.3f}; "
          f"published Tu {got.seen[0]:.2f} s, Tg {got.seen[1]:.1f} s (read: {tu:.2f} s, {tg:.1f} s)")
    assert abs(got.planned - slow) > 0.05  # the plan is not the read: the checks below tell them apart
    assert got.seen[1] == pytest.approx(tg, rel=0.01)
    assert got.seen[0] == pytest.approx(tu, rel=0.02)


@pytest.mark.parametrize("seed", FAST_BLOCK_SEEDS)
def test_a_faster_block_gets_its_brake_planned_on_its_own_fast_lag(seed: int) -> None:
    """A brake is timed on the fast lag: a block 30 % faster, its slow lag the model's, overshot 2.27 and
    2.28 % on these noise draws with the model's brake. The line's level shows the fast lag, and a
    brake is planned again on it."""
    got = step(block=0.7, seed=seed)
    print(f"block x0.7, noise draw {seed}: settling {got.settling_s / got.bound_s:.2f} x the bound, "
          f"overshoot {got.overshoot_pct:.2f} %")
    assert got.overshoot_pct <= MISMATCH_OVERSHOOT_GOAL
    assert got.settling_s <= MISMATCH_BOUND_RATIO_GOAL * got.bound_s


def test_a_plant_ahead_of_the_path_gets_its_integral_before_it_passes_w() -> None:
    """A stronger heater than the model's runs past W at the model's holding power. Its integral acts once X
    runs ahead of the path (waiting for the path to reach the band let one draw overshoot 3.50 % instead of
    2.54 % with the lag as read); planned on the shortest slow lag the rise allows, the path runs ahead of
    the plant for longer, so that share is small now (a mean of 3.14 % without it, 3.00 % with it), but the
    overshoot no longer depends on how long the noise made the lag read. It still misses the mismatch goal
    (the expected failure above), which is the one draw CI runs."""
    skip_unless_slow("gain x1.2 over noise draws")
    runs = [step(gain=1.2, seed=seed) for seed in NOMINAL_SEEDS]
    overshoots = [r.overshoot_pct for r in runs]
    print(f"gain x1.2, noise draws {NOMINAL_SEEDS.start}-{NOMINAL_SEEDS.stop - 1}: overshoot "
          f"{', '.join(f'{o:.2f}' for o in overshoots)} % (mean {np.mean(overshoots):.2f} %), settling "
          f"{', '.join(f'{r.settling_s / r.bound_s:.2f}' for r in runs)} x the bound")
    assert float(np.mean(overshoots)) <= STRONGER_HEATER_MEAN_MAX
    assert max(overshoots) <= STRONGER_HEATER_WORST_MAX
