"""The tune-end fit's benchmark measures the fit on records it identifies, not a program that fails early."""

from __future__ import annotations

from plc.bench_tunefit import RECORDS, fit_cost, spread_cost


def test_the_fit_bench_identifies_the_model_of_each_record():
    first_order, two_lags = RECORDS
    cost, model = fit_cost(first_order, quick=True)
    assert cost > 0.0 and model.startswith("order 1, Ks 0.592")
    cost, model = fit_cost(two_lags, quick=True)
    assert cost > 0.0 and model.startswith("two lags")


def test_the_fit_bench_spreads_the_fit_over_cycles():
    cycles, longest_ms = spread_cost(RECORDS[0])
    assert cycles > 1 and longest_ms > 0.0
