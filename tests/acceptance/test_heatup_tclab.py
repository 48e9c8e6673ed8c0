"""The model-based setpoint response through Modbus on the TCLab (scenario t4_tclab, variant "model-based
PID"): two heaters on one board, zone 1 tuned while zone 2 is idle, then stepped 45 -> 60 degC while zone 2
holds its own setpoint. TUNE fits two unequal lags to a plant of three coupled states, so the model the
plan starts from is not the plant the step meets; the rise's line re-plans on the lags it shows. Goals on
the true temperature: 2 % settling within 1.05x the bang-hold bound of the true plant (one switch, which
overshoots about 2 % to enter the band early) with overshoot <= 0.5 %.
The step holds at the power TUNE's gain gives, so its overshoot follows the error in Ks. The scenario ends
zone 1's TUNE at 95 % of the way to its setpoint: cut at the default 80 %, the record held about half of
the tune step's rise, where the slow lag shows Ks only through Ks/Tg, and over noise draws Ks came out 9 %
low to 22 % high (the step overshot up to 2.42 %, or crept in for up to 2.3x the bound). Over DRAWS
(THERMOST_SLOW=1) the mean overshoot is held to the nominal goal and every draw to the mismatch overshoot."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from modbus_bridge.scenario import load_scenario, resolve_scenario
from tests.slow_cases import skip_unless_slow

from .heatup_step import ScoredStep, model_based_step

SCENARIO = "t4_tclab"
BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, NOMINAL_OVERSHOOT_PCT = 1.05, 2.0, 0.5
DRAWS = range(1, 9)  # noise draws other than the scenario's own


@pytest.fixture(scope="module")
def tclab_step(harness) -> ScoredStep:
    return model_based_step(harness, load_scenario(resolve_scenario(SCENARIO)), SCENARIO)


def test_the_tclab_step_enters_the_band_with_the_bound_and_within_the_nominal_overshoot(tclab_step):
    assert tclab_step.settling_s <= BOUND_RATIO * tclab_step.bound_s
    assert tclab_step.overshoot_pct <= NOMINAL_OVERSHOOT_PCT


def test_over_noise_draws_the_mean_overshoot_meets_the_nominal_goal(harness):
    skip_unless_slow(f"{SCENARIO} over noise draws {DRAWS.start}-{DRAWS.stop - 1}")
    sc = load_scenario(resolve_scenario(SCENARIO))
    steps = [model_based_step(harness, dataclasses.replace(sc, seed=seed), f"{SCENARIO} noise draw {seed}")
             for seed in DRAWS]
    overshoots, ratios = [s.overshoot_pct for s in steps], [s.ratio for s in steps]
    print(f"{SCENARIO}, noise draws {DRAWS.start}-{DRAWS.stop - 1}: overshoot "
          f"{', '.join(f'{o:.2f}' for o in overshoots)} % (mean {np.mean(overshoots):.2f} %), settling "
          f"{', '.join(f'{r:.2f}' for r in ratios)} x the bound (median {np.median(ratios):.2f} x)")
    assert float(np.mean(overshoots)) <= NOMINAL_OVERSHOOT_PCT
    assert max(overshoots) <= MISMATCH_OVERSHOOT_PCT
