"""Metrics against python-control's step_info on the same traces, and hand-checkable cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from modbus_bridge.metrics import (
    StepWindow,
    disturbance_metrics,
    effort_metrics,
    error_integrals,
    json_safe,
    settled_noise_metrics,
    settling_time,
    step_metrics,
)

control = pytest.importorskip("control", reason="python-control is the metrics oracle")


def underdamped(zeta: float, wn: float, t: np.ndarray) -> np.ndarray:
    sys = control.tf([wn * wn], [1.0, 2 * zeta * wn, wn * wn])
    return control.step_response(sys, t).outputs


@pytest.mark.parametrize(("zeta", "wn"), [(0.3, 0.5), (0.6, 0.2), (1.2, 0.3)])
def test_step_metrics_match_step_info(zeta, wn):
    t = np.arange(0.0, 120.0, 0.05)
    y = underdamped(zeta, wn, t)
    info = control.step_info(y, t, final_output=1.0)
    m = step_metrics(StepWindow(t=t, y=y, t0=0.0, y0=0.0, y_final=1.0))
    assert m["rise_time_s"] == pytest.approx(info["RiseTime"], abs=1e-9)
    assert m["settling_time_2pct_s"] == pytest.approx(info["SettlingTime"], abs=1e-9)
    assert m["overshoot_pct"] == pytest.approx(info["Overshoot"], abs=1e-9)
    info5 = control.step_info(y, t, final_output=1.0, SettlingTimeThreshold=0.05)
    assert m["settling_time_5pct_s"] == pytest.approx(info5["SettlingTime"], abs=1e-9)


def test_offset_and_time_shifted_step_equals_normalised_step_info():
    """A step 160 -> 200 °C at t0 = 300 s gives the same figures as the normalised trace."""
    tn = np.arange(0.0, 150.0, 0.1)
    yn = underdamped(0.45, 0.15, tn)
    info = control.step_info(yn, tn, final_output=1.0)
    t, y = tn + 300.0, 160.0 + 40.0 * yn
    m = step_metrics(StepWindow(t=t, y=y, t0=300.0, y0=160.0, y_final=200.0))
    assert m["rise_time_s"] == pytest.approx(info["RiseTime"], abs=1e-9)
    assert m["settling_time_2pct_s"] == pytest.approx(info["SettlingTime"], abs=1e-9)
    assert m["overshoot_pct"] == pytest.approx(info["Overshoot"], abs=1e-9)
    assert m["peak_c"] == pytest.approx(160.0 + 40.0 * info["Peak"], abs=1e-9)


def test_downward_step():
    t = np.arange(0.0, 100.0, 0.1)
    y = 50.0 - 30.0 * underdamped(0.5, 0.3, t)
    info = control.step_info(underdamped(0.5, 0.3, t), t, final_output=1.0)
    m = step_metrics(StepWindow(t=t, y=y, t0=0.0, y0=50.0, y_final=20.0))
    assert m["overshoot_pct"] == pytest.approx(info["Overshoot"], abs=1e-9)
    assert m["settling_time_2pct_s"] == pytest.approx(info["SettlingTime"], abs=1e-9)


def test_dead_time_and_delay_time_of_fopdt():
    t = np.arange(0.0, 200.0, 0.1)
    lag, tau = 10.6, 23.4
    y = np.where(t > lag, 1.0 - np.exp(-(t - lag) / tau), 0.0)
    m = step_metrics(StepWindow(t=t, y=y, t0=0.0, y0=0.0, y_final=1.0))
    assert m["dead_time_s"] == pytest.approx(lag + tau * -math.log(1 - 0.02), abs=0.11)
    assert m["delay_time_s"] == pytest.approx(lag + tau * math.log(2), abs=0.11)
    assert m["overshoot_pct"] == 0.0


def test_error_integrals_closed_form():
    t = np.linspace(0.0, 10.0, 10001)
    e = np.exp(-t)
    r = error_integrals(t, e, 0.0)
    assert r["iae_c_s"] == pytest.approx(1 - math.exp(-10), rel=1e-6)
    assert r["ise_c2_s"] == pytest.approx(0.5 * (1 - math.exp(-20)), rel=1e-6)
    assert r["itae_c_s2"] == pytest.approx(1 - 11 * math.exp(-10), rel=1e-6)


def test_steady_state_band_and_unsettled_trace():
    t = np.arange(0.0, 100.0, 0.1)
    y = np.ones_like(t)
    y[t > 50] += 0.01 * np.sin(t[t > 50])
    m = step_metrics(StepWindow(t=t, y=y, t0=0.0, y0=0.0, y_final=1.0))
    assert m["ss_peak_to_peak_c"] == pytest.approx(0.02, abs=1e-3)
    assert settling_time(t, 0.5 * np.ones_like(t), 1.0, 0.02, 0.0) != settling_time(t, y, 1.0, 0.02, 0.0)
    assert math.isnan(settling_time(t, 0.5 * np.ones_like(t), 1.0, 0.02, 0.0))


def test_disturbance_recovery_time():
    t = np.arange(0.0, 60.0, 0.1)
    y = np.full_like(t, 200.0)
    hit = (t >= 10.0) & (t < 30.0)
    y[hit] = 200.0 - 2.0 * np.sin(np.pi * (t[hit] - 10.0) / 20.0)
    m = disturbance_metrics(t, y, 200.0, 10.0, 0.8)
    assert m["max_deviation_c"] == pytest.approx(-2.0, abs=1e-3)
    # back inside +/-0.8 when sin(pi s/20) < 0.4 on the way down: s = 20 - 20 asin(0.4)/pi
    expected = 20.0 - 20.0 * math.asin(0.4) / math.pi
    assert m["recovery_time_2pct_s"] == pytest.approx(expected, abs=0.11)


def test_effort_metrics():
    t = np.arange(0.0, 60.0, 1.0)
    u = np.array([0.0, 100.0] * 30)
    pwm = (u > 50).astype(int)
    m = effort_metrics(t, u, 0.0, 100.0, pwm)
    assert m["tv_output_pct"] == pytest.approx(100.0 * 59)
    assert m["saturation_time_s"] == pytest.approx(60.0)
    assert m["pwm_switches_per_min"] == pytest.approx(59 / (59 / 60))


def test_settled_noise_metrics_on_a_known_ripple():
    t = np.arange(0.0, 100.0, 0.1)
    output = 40.0 + 2.0 * np.sin(2 * np.pi * t / 10.0)  # std 2 / sqrt(2)
    true_c = 200.3 + 0.25 * np.sin(2 * np.pi * t / 10.0)
    got = settled_noise_metrics(t, output, true_c, 200.0, 50.0)
    assert got["ss_output_std_pct"] == pytest.approx(2.0 / math.sqrt(2.0), rel=1e-2)
    assert got["ss_true_ripple_c"] == pytest.approx(0.25, rel=1e-3)
    assert got["ss_true_offset_c"] == pytest.approx(0.3, abs=1e-3)
    assert settled_noise_metrics(t, output, true_c, 200.0, math.nan) == {}  # never settled
    assert settled_noise_metrics(t, output[:10], true_c, 200.0, 50.0) == {}  # output not recorded


def test_json_safe():
    assert json_safe({"a": math.nan, "b": 1.0, "c": math.inf}) == {"a": None, "b": 1.0, "c": None}
