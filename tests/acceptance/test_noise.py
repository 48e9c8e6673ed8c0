"""Noise handling through Modbus: seed 002's hot end self-tuned with 0.2 degC of sensor noise (four times the
shipped scenario's 0.05). The tuner measures the noise at rest and sizes the actual-value filter from it
(fTFilterTuned, at most fTuneFilterLagShare of the identified dead time) and publishes the robustness of
the set with that filter's lag (fMsTuned). The product's goals once the loop holds 200 degC: controller
output standard deviation <= 1 %, true-temperature ripple <= +-0.1 degC, no offset.
"""

from __future__ import annotations

import dataclasses

import pytest

from modbus_bridge.runner import HarnessSetup
from modbus_bridge.scenario import load_scenario, resolve_scenario

from .conftest import run_scenario

SENSOR_NOISE_C = 0.2  # sensor noise standard deviation of the goal, degC
OUTPUT_STD_GOAL_PCT = 1.0
RIPPLE_GOAL_C = 0.1  # half the peak-to-peak of the true temperature
# the noise must not shift the mean temperature: half the ripple goal, so an offset cannot use up the band,
# and a quarter of the sensor's standard deviation (what a biased filter or quantisation would show)
OFFSET_BOUND_C = 0.05
LAG_SHARE_DEFAULT = 0.1  # fTuneFilterLagShare's default (plc/app/tags.tsv)
MS_FRAGILE = 2.0  # above: a fragile loop (FC_CtrlMaxSensitivity)
VARIANT = "PID (self-tuned)"

# measured on this branch (seed 2, PID variant): the tuner identifies L = 0.51 s instead of 1.05 s at this
# noise, so SIMC gives Kp = 37 %/degC; the P part alone then moves the output by 37 * 0.2 = 7.4 % (std)
# and a filter held below 0.1 L removes little of it (Tf = 0.05 s)
SHORTFALL_STD = "output std 10.3 % at 0.2 degC noise (goal 1 %): Kp 37 %/degC from an identified L of 0.51 s"
SHORTFALL_RIPPLE = "true ripple +-0.49 degC at 0.2 degC noise (goal 0.1): the output noise of Kp 37 %/degC"


def _noisy_seed002(harness: HarnessSetup) -> list:
    sc = load_scenario(resolve_scenario("seed002_hotend_40w"))
    zone = sc.zones[0]
    zone = dataclasses.replace(zone, sensor=dataclasses.replace(zone.sensor, noise_sigma_c=SENSOR_NOISE_C))
    tune, hold = zone.phases[0], zone.phases[1]
    zone = dataclasses.replace(zone, phases=[tune, hold])
    sc = dataclasses.replace(sc, zones=[zone], variants=[v for v in sc.variants if v.name == VARIANT])
    ((result, metrics),) = run_scenario(harness, sc)
    assert result.error is None, result.error
    return metrics


@pytest.fixture(scope="module")
def noisy(harness):
    """The tune and hold phases' metrics (one closed-loop run for the module)."""
    return {m.phase: m for m in _noisy_seed002(harness)}


def test_tuning_succeeds_and_sizes_the_filter_within_its_lag_bound(noisy):
    tune = noisy["tune"]
    assert tune.outcome == "ok", f"tuning did not complete at {SENSOR_NOISE_C} degC noise: {tune.outcome}"
    v = tune.values
    tu, tf, ms = v["identified_tu_s"], v["tuned_filter_s"], v["tuned_ms"]
    assert tu > 0.0
    # the P part's noise at this level needs more filtering than the bound allows: the bound is reached
    assert 0.0 < tf <= LAG_SHARE_DEFAULT * tu * (1.0 + 1e-3), f"Tf = {tf:.3g} s, L = {tu:.3g} s"
    # Ms includes the filter lag and the published set stays clear of a fragile loop
    assert 1.0 < ms <= MS_FRAGILE, f"Ms = {ms:.3g}"


def test_no_offset(noisy):
    offset = noisy["hold"].values["ss_true_offset_c"]
    assert abs(offset) <= OFFSET_BOUND_C, f"true-temperature offset {offset:+.3f} degC"


@pytest.mark.xfail(reason=SHORTFALL_STD, strict=True)
def test_output_std_at_most_1_percent(noisy):
    std = noisy["hold"].values["ss_output_std_pct"]
    assert std <= OUTPUT_STD_GOAL_PCT, f"output std {std:.2f} %"


@pytest.mark.xfail(reason=SHORTFALL_RIPPLE, strict=True)
def test_true_ripple_at_most_0_1_degc(noisy):
    ripple = noisy["hold"].values["ss_true_ripple_c"]
    assert ripple <= RIPPLE_GOAL_C, f"true ripple +-{ripple:.3f} degC"
