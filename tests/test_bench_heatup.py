"""The setpoint response's benchmark times what it names: on two unequal lags the rise it feeds is the
model's own, so the line through it is fitted and reads the model's lags (the fit's scan is among those
timed); fed a faster chain's rise, it reads the faster lags and plans again on a shorter one within the
line's errors (those fits timed too); and every model gets a response from rest."""

from __future__ import annotations

import pytest

from plc.bench_adapter import library_sources
from plc.bench_heatup import FASTER_PLANT, NLAG_ORDER, RESTART_SCANS, TWO_LAG_RATIO, heatup_cost, program
from plc.st.compiler import load_application


def lag_fits(plant_scale: float) -> list[tuple[float, float, float]]:
    """(slow, fast, planned slow) lag scales of each response's line in the two-lag bench program."""
    app = load_application(library_sources()
                           + [("bench_program.st", program(True, 2, TWO_LAG_RATIO, plant_scale))])
    fits = []
    done_before = False
    for _ in range(2 * RESTART_SCANS):
        app.scan()
        done = app.get("inst0.fbHu.bLagLineDone")
        if done and not done_before:
            fits.append((app.get("inst0.fbHu.fLagScale"), app.get("inst0.fbHu.fFastScale"),
                         app.get("inst0.fbHu.fLagPlanScale")))
        done_before = done
    assert fits, "the rise never passed its second crossing"
    return fits


def test_the_two_lag_bench_fits_the_model_s_own_lags() -> None:
    for slow, fast, _ in lag_fits(1.0):
        assert slow == pytest.approx(1.0, abs=0.01) and fast == pytest.approx(1.0, abs=0.01)


def test_the_faster_two_lag_bench_plans_again_on_a_shorter_lag() -> None:
    for slow, fast, planned in lag_fits(FASTER_PLANT):
        assert slow == pytest.approx(FASTER_PLANT, abs=0.02) and fast == pytest.approx(FASTER_PLANT, abs=0.05)
        assert planned < slow


MODELS = [(1, 0.0, 1.0), (NLAG_ORDER, 0.0, 1.0), (2, TWO_LAG_RATIO, 1.0), (2, TWO_LAG_RATIO, FASTER_PLANT)]


@pytest.mark.parametrize(("order", "ratio", "scale"), MODELS)
def test_each_model_runs_responses_and_reports_its_longest_scan(order: int, ratio: float,
                                                                 scale: float) -> None:
    cost, active, longest = heatup_cost(True, order, ratio, scale)
    assert active > 0.3
    assert longest > 0.0 and cost >= 0.0
