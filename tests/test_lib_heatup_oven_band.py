"""The oven's model-based step (four equal lags, 100 -> 150 degC, test_lib_heatup's oven) over a grid of
plants unlike its model, not only at the ends of the band: lags 0.7 .. 1.3 times the model's and a
gain 0.8 .. 1.2 times it, every combination. The mismatch goals are 2 % overshoot within 1.5x that plant's
bang-hold bound. The cases that miss them run as strict expected failures, so a plan that lands them shows;
docs/library.md shows the grid (figures:heatup-oven-band, checked here against the results of this process).

The ends hold. The pulse is over before a chain of lags passes it on, so the limit phase cannot see them;
the rise after it, at the holding power, shows them. Shorter lags hold more of the pulse than the plan
allowed for: a brake takes it off (with the PID pulling X back onto the model's path instead: 560 s, 3.5x
the bound). Longer lags: the rest of the path follows them, and the PID does not wind its integral up
pushing the plant onto the model's time scale (on the model's path throughout: 962 s, 17 %). A gain off the
model's makes the model's holding power land X off W, which the rise to its first point alone cannot tell
from other lags; the time it takes to rise from there to twice as far can: the second plan brakes or boosts
and holds at the plant's own power (on the model's path, the PID taking the difference: 548 s for 0.8,
354 s and 6.1 % for 1.2).

Two causes, seen in the second plan's fit (FC_HeatUpNLagFit, printed by a debug run of the scan):
- a gain 10 % off the model's, with the lags off too, is read within fGainKeep of 1 and kept as the model's,
  so the plan holds at the model's power, 10 % off the plant's: the PID's integral takes that away only
  slowly. That band is there because a delay 30 % off reads as 7 to 9 % of gain; at fGainKeep 0.05 these
  cases pass, and the delay cases miss the goals instead;
- a plant both faster and stronger: its rise shows it only after the pulse planned on the model has ended,
  by the second point the chain may already hold more heat than W needs even with the heater off (lags 0.7,
  gain 1.2: the peak is the same for every brake longer than a minute)."""

from __future__ import annotations

import functools

import pytest

from modbus_bridge import docfigures
from tests.test_lib_heatup import MISMATCH_BOUND_RATIO, MISMATCH_OVERSHOOT_PCT, OVEN_N, oven_bound, oven_step

LAGS = (0.7, 0.8, 0.9, 1.0, 1.1, 1.3)  # times the model's
GAINS = (0.8, 0.9, 1.0, 1.1, 1.2)
GAIN_KEPT = "a gain 10 % off read as the model's: held at the model's power"
FASTER_AND_STRONGER = "faster and stronger: the chain holds too much heat by the second point"
SHORTFALLS = {
    (0.7, 0.9): GAIN_KEPT,
    (0.7, 1.1): FASTER_AND_STRONGER,
    (0.7, 1.2): FASTER_AND_STRONGER,
    (0.8, 1.1): GAIN_KEPT,
    (0.8, 1.2): FASTER_AND_STRONGER,
    (0.9, 1.1): GAIN_KEPT,
    (0.9, 1.2): FASTER_AND_STRONGER,
    (1.1, 0.9): GAIN_KEPT,
    (1.1, 1.1): GAIN_KEPT,
    (1.3, 0.9): GAIN_KEPT,
}


@functools.cache
def band_case(lags: float, gain: float) -> tuple[float, float, float]:
    """(2 % settling s, overshoot %, bound s) of the oven's step with its lags and gain this far off."""
    res = oven_step(order=OVEN_N, t_scale=lags, k_scale=gain)
    return res.settling_s, res.overshoot_pct, oven_bound(lags, gain)


def meets_goals(lags: float, gain: float) -> bool:
    settling, overshoot, bound = band_case(lags, gain)
    return overshoot <= MISMATCH_OVERSHOOT_PCT and settling <= MISMATCH_BOUND_RATIO * bound


def _cases():
    for lags in LAGS:
        for gain in GAINS:
            why = SHORTFALLS.get((lags, gain))
            marks = [pytest.mark.xfail(reason=f"known shortfall: {why}", strict=True)] if why else []
            yield pytest.param(lags, gain, marks=marks, id=f"lags_x{lags}-gain_x{gain}")


@pytest.mark.parametrize(("lags", "gain"), list(_cases()))
def test_the_oven_step_keeps_the_mismatch_goals_across_the_grid(lags: float, gain: float) -> None:
    settling, overshoot, bound = band_case(lags, gain)
    print(f"oven lags x{lags}, gain x{gain}: {settling:.1f} s (bound {bound:.1f} s, "
          f"{settling / bound:.2f}x), {overshoot:.2f} %")
    assert overshoot <= MISMATCH_OVERSHOOT_PCT
    assert settling <= MISMATCH_BOUND_RATIO * bound


def test_the_docs_show_this_grid() -> None:
    """docs/library.md's grid, from the cases this process computed."""
    text = (docfigures.DOCS / "library.md").read_text(encoding="utf-8")
    assert "<!-- figures:heatup-oven-band -->" in text
    assert docfigures.render(text, {"heatup-oven-band"}) == text, (
        "docs/library.md: figures:heatup-oven-band disagrees with the code: run `make docs`"
    )
