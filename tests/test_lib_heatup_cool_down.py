"""A cool-down on the bench oven's chain of lags mirrors its heat-up: the pulse at the low limit, the hold
phase at the holding power while the fall shows the lags, the second plan, and the landing within the
mismatch goals with the lags as planned or 30 % off."""

from __future__ import annotations

import numpy as np
import pytest

from modbus_bridge.plants.response import PlantModel, bang_hold_bound
from tests.test_lib_heatup import (
    ACTIVE,
    BAND,
    MISMATCH_BOUND_RATIO,
    MISMATCH_OVERSHOOT_PCT,
    OVEN_AMBIENT,
    OVEN_K,
    OVEN_L,
    OVEN_N,
    OVEN_T,
    OVEN_TS,
    oven_tuned,
)

# the oven rests at 100 degC at 0 % (the plant's offset): up to 150 first, then down to 125, so that the
# holding power of the cool-down (11 %) lies inside the output range
START_C, HIGH_C, LOW_C = 100.0, 150.0, 125.0
SETTLE_S, HORIZON_S = 1500.0, 1200.0
HOLD_STATE = 3


def oven_cool_down(t_scale: float) -> tuple[float, float, set[int]]:
    """Settling time, overshoot past W (below it) in % of the step and the heat-up states seen."""
    drv, plant, dist = oven_tuned(OVEN_N, START_C, t_scale=t_scale)
    rng = np.random.default_rng(7)
    drv.set("fbUut.fW1", HIGH_C)
    drv.set("nMode", ACTIVE)
    start = round(SETTLE_S / OVEN_TS)
    xs, states = [], set()
    for n in range(start + round(HORIZON_S / OVEN_TS)):
        if n == start:
            drv.set("fbUut.fW1", LOW_C)
        drv.set("fbUut.fX", plant.temperatures()[0] + rng.normal(0.0, 0.03))
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("nState") == ACTIVE, f"state {drv.get('nState')}, alarm {drv.get('fbUut.dwAlarm'):#x}"
        if n >= start:
            xs.append(plant.temperatures()[0])
            states.add(drv.get("fbUut.nHeatUpState"))
        plant.step([drv.get("fbUut.fY")], OVEN_TS, dist)
    step = HIGH_C - LOW_C
    outside = [i for i, x in enumerate(xs) if abs(x - LOW_C) > BAND * step]
    settling = (outside[-1] + 1) * OVEN_TS if outside else 0.0
    return settling, max(0.0, LOW_C - min(xs)) / step * 100.0, states


@pytest.mark.parametrize("t_scale", [1.0, 0.7, 1.3])
def test_a_cool_down_on_the_oven_mirrors_its_heat_up(t_scale: float) -> None:
    model = PlantModel("nlag", dict(gain_c_per_pct=OVEN_K, time_constant_s=OVEN_T * t_scale,
                                    order=float(OVEN_N), dead_time_s=OVEN_L, ambient_c=OVEN_AMBIENT))
    bound = bang_hold_bound(model, HIGH_C, LOW_C, OVEN_TS, 600.0).settling_s
    settling, overshoot, states = oven_cool_down(t_scale)
    print(f"oven {HIGH_C:.0f} -> {LOW_C:.0f} degC, lags x{t_scale}: {settling:.1f} s (bound {bound:.1f} s, "
          f"{settling / bound:.2f}x), {overshoot:.2f} % below W")
    assert HOLD_STATE in states
    assert overshoot <= MISMATCH_OVERSHOOT_PCT
    assert settling <= MISMATCH_BOUND_RATIO * bound
