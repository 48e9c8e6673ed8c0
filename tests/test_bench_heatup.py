"""The setpoint response's benchmark times what it names: on two unequal lags the rise it feeds is the
model's own, so the line through it is fitted and reads the model's lags (the fit's scan is among those
timed), and every model gets a response from rest."""

from __future__ import annotations

import pytest

from plc.bench_adapter import library_sources
from plc.bench_heatup import NLAG_ORDER, RESTART_SCANS, TWO_LAG_RATIO, heatup_cost, program
from plc.st.compiler import load_application


def test_the_two_lag_bench_fits_the_model_s_own_lags() -> None:
    app = load_application(library_sources() + [("bench_program.st", program(True, 2, TWO_LAG_RATIO))])
    fits = []
    done_before = False
    for _ in range(2 * RESTART_SCANS):
        app.scan()
        done = app.get("inst0.fbHu.bLagLineDone")
        if done and not done_before:
            fits.append((app.get("inst0.fbHu.fLagScale"), app.get("inst0.fbHu.fFastScale")))
        done_before = done
    assert fits, "the rise never passed its second crossing"
    for slow, fast in fits:
        assert slow == pytest.approx(1.0, abs=0.01) and fast == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize(("order", "ratio"), [(1, 0.0), (NLAG_ORDER, 0.0), (2, TWO_LAG_RATIO)])
def test_each_model_runs_responses_and_reports_its_longest_scan(order: int, ratio: float) -> None:
    cost, active, longest = heatup_cost(True, order, ratio)
    assert active > 0.3
    assert longest > 0.0 and cost >= 0.0
