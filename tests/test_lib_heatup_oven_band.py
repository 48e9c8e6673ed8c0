"""The oven's model-based step (four equal lags, 100 -> 150 degC, test_lib_heatup's oven) over a band of
plants unlike its model, not only at the band's ends: lags 0.7 .. 1.3 times the model's and a gain 0.8 ..
1.2 times it, one at a time and at the corners. Every case keeps the mismatch goals (2 % overshoot within
1.5x that plant's bang-hold bound) except a plant both faster and stronger than its model: its rise shows
the plant only after a pulse planned on the model has ended, and the second plan's brake, made where the rise
passes its second point, can then either keep the peak or avoid the dip, not both (it balances them).
Those cases run as strict expected failures with THERMOST_SLOW=1, so a plan that lands them shows; CI runs
the rest of the band (about 15 s of scans on one worker)."""

from __future__ import annotations

import pytest

from tests.slow_cases import skip_known_shortfall
from tests.test_lib_heatup import MISMATCH_BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, OVEN_N, oven_bound, oven_step

BAND = [(0.75, 1.0), (0.8, 1.0), (0.9, 1.0), (1.1, 1.0), (1.0, 0.9), (1.0, 1.1), (1.0, 1.15),
        (0.7, 0.8), (0.8, 0.8), (1.3, 0.8), (1.2, 1.2), (1.3, 1.2)]  # (lags, gain) times the model's
FASTER_AND_STRONGER = {
    (0.7, 1.2): "brake balanced at about +10 % peak and -10 % dip",
    (0.8, 1.2): "about 4 % overshoot, 1.9x",
    (0.8, 1.1): "about 7 % overshoot, 1.7x",
    (0.9, 1.2): "within 2 % but about 1.9x the bound",
}


def _cases():
    for lags, gain in BAND:
        yield pytest.param(lags, gain, None, id=f"lags_x{lags}-gain_x{gain}")
    for (lags, gain), why in FASTER_AND_STRONGER.items():
        mark = pytest.mark.xfail(reason=f"known shortfall: {why}", strict=True)
        yield pytest.param(lags, gain, why, marks=[mark], id=f"lags_x{lags}-gain_x{gain}")


@pytest.mark.parametrize(("lags", "gain", "shortfall"), list(_cases()))
def test_the_oven_step_keeps_the_mismatch_goals_across_the_band(lags: float, gain: float,
                                                                shortfall: str | None) -> None:
    label = f"oven lags x{lags}, gain x{gain}"
    if shortfall:
        skip_known_shortfall(label, shortfall)
    res, bound = oven_step(order=OVEN_N, t_scale=lags, k_scale=gain), oven_bound(lags, gain)
    print(f"{label}: {res.settling_s:.1f} s (bound {bound:.1f} s, {res.settling_s / bound:.2f}x), "
          f"{res.overshoot_pct:.2f} %")
    assert res.overshoot_pct <= MISMATCH_OVERSHOOT_PCT
    assert res.settling_s <= MISMATCH_BOUND_RATIO * bound
