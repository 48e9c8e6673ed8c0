"""True-model pieces of the optimiser and scorecard: the bang-hold bound and the one with a brake, Ms against
python-control, SIMC/AMIGO against the formulas of control.md, the numerical frequency response of a
nonlinear plant."""

from __future__ import annotations

import math

import numpy as np
import pytest

from modbus_bridge.optimise.experiment import PidGains
from modbus_bridge.optimise.robustness import amigo, loop_model, operating_point, simc
from modbus_bridge.plants import response
from modbus_bridge.plants.response import (
    FopdtFit,
    PlantModel,
    bang_brake_hold_bound,
    bang_hold_bound,
    exact_frequency_response,
    frequency_response_from_step,
    step_response,
)
from modbus_bridge.scenario import load_scenario, resolve_scenario

SEED003 = PlantModel(
    "fopdt", {"gain_c_per_pct": 0.5916, "time_constant_s": 23.4, "dead_time_s": 10.6, "ambient_c": 160.0}
)


def test_bang_hold_bound_on_seed003():
    b = bang_hold_bound(SEED003, 160.0, 200.0, 0.1, 150.0)
    # full power until the undelayed state is close to 200 °C, then 40/0.5916 = 67.6 % holds it
    assert b.u_full == 100.0 and b.u_hold == pytest.approx(40.0 / 0.5916, rel=1e-6)
    # closed form: the band (39.2 °C rise) is entered L + T ln(K·100/(K·100 − 39.2)) after the step
    k = 0.5916 * 100.0
    entry = 10.6 + 23.4 * np.log(k / (k - 39.2))
    assert b.settling_s == pytest.approx(entry, abs=0.11)
    assert b.overshoot_pct < 2.0


@pytest.mark.parametrize(
    "pm, y0, r",
    [
        (PlantModel("transfer_function", {"num": (0.6,), "den": (2338.0, 156.7, 1.0), "dead_time_s": 0.35,
                                          "ambient_c": 21.0}), 45.0, 60.0),
        (PlantModel("nlag", {"gain_c_per_pct": 2.0, "time_constant_s": 40.0, "order": 3, "dead_time_s": 2.0,
                             "ambient_c": 25.0}), 120.0, 70.0),
    ],
    ids=["two_lags_heating", "n_lag_cooling"],
)
def test_the_superposed_bound_of_a_linear_plant_is_the_simulated_one(pm, y0, r, monkeypatch):
    fast = bang_hold_bound(pm, y0, r, 0.25, 400.0)
    monkeypatch.setattr(response, "_is_linear", lambda _plant: False)
    slow = bang_hold_bound(pm, y0, r, 0.25, 400.0)
    assert fast.settling_s < 300.0
    assert (fast.switch_s, fast.settling_s) == (slow.switch_s, slow.settling_s)
    assert fast.overshoot_pct == pytest.approx(slow.overshoot_pct, abs=1e-9)
    assert np.max(np.abs(fast.y - slow.y)) < 1e-9


def _chain_step(x: np.ndarray, order: int) -> np.ndarray:
    """Unit step response of n equal unit lags at x = t / T (0 before the step)."""
    x = np.maximum(x, 0.0)
    return 1.0 - np.exp(-x) * sum(x**k / math.factorial(k) for k in range(order))


def test_a_brake_between_full_and_holding_power_settles_a_chain_of_lags_sooner():
    """Three equal lags: the bang-brake-hold search (a grid refined around its best) finds the optimum that
    a brute force over every pair of switch times on the same dt finds in the chain's closed-form response,
    and beats one switch; on a first-order lag a brake gains nothing; a plant that is not superposable gets
    no such bound."""
    k, tau, order, delay, ambient = 2.0, 20.0, 3, 1.0, 25.0
    chain = PlantModel("nlag", {"gain_c_per_pct": k, "time_constant_s": tau, "order": order,
                                "dead_time_s": delay, "ambient_c": ambient})
    y0, r, dt, horizon = 80.0, 120.0, 0.5, 600.0
    one = bang_hold_bound(chain, y0, r, dt, horizon)
    two = bang_brake_hold_bound(chain, y0, r, dt, horizon)
    assert two is not None and (two.u_full, two.u_brake) == (100.0, 0.0) and two.brake_s > 0.0
    assert two.settling_s < 0.9 * one.settling_s and two.overshoot_pct < 2.0
    u0, uh = (y0 - ambient) / k, (r - ambient) / k
    t = dt * np.arange(1, round(horizon / dt) + 1)
    best = math.inf
    for a in np.arange(0.0, 100.0, dt):
        for b in np.arange(0.0, 60.0, dt):
            y = ambient + k * (u0 + (100.0 - u0) * _chain_step((t - delay) / tau, order)
                               - 100.0 * _chain_step((t - a - delay) / tau, order)
                               + uh * _chain_step((t - a - b - delay) / tau, order))
            best = min(best, response._settling(t, y, y0, r))
    assert two.settling_s == pytest.approx(best, abs=1e-6)
    print(f"three lags: one switch {one.settling_s:.1f} s, with a brake {two.settling_s:.1f} s "
          f"({two.pulse_s:.1f} s full, {two.brake_s:.1f} s off; brute force {best:.1f} s)")
    first_order = bang_brake_hold_bound(SEED003, 160.0, 200.0, 0.1, 150.0)
    assert first_order is not None
    one_switch = bang_hold_bound(SEED003, 160.0, 200.0, 0.1, 150.0)
    assert first_order.settling_s == pytest.approx(one_switch.settling_s)
    assert bang_brake_hold_bound(PlantModel("tclab", {}), 45.0, 60.0, 0.5, 1000.0) is None


def test_numerical_frequency_response_matches_the_transfer_function():
    t, s, _ = step_response(SEED003, 200.0, dt=0.05)
    w = np.logspace(-3, 0.5, 40)
    exact = exact_frequency_response(SEED003.build(), w)
    assert np.max(np.abs(frequency_response_from_step(t, s, w) - exact) / np.abs(exact)) < 1e-3


def test_ms_matches_python_control_on_a_delay_free_loop():
    control = pytest.importorskip("control", reason="python-control (dev dependency) is the oracle")
    from modbus_bridge.optimise.robustness import LoopModel
    from modbus_bridge.plants import NLag

    w = np.logspace(-4, 1, 1500)
    lm = LoopModel(w, exact_frequency_response(NLag(2.2, 45.0, 4), w), FopdtFit(1, 1, 1), 0.0)
    s = control.tf("s")
    plant = control.tf([2.2], list(np.poly1d([45.0, 1.0]) ** 4))
    c = 1.2 * (1 + 1 / (120.0 * s) + 20.0 * s / (5.0 * s + 1))
    resp = control.frequency_response(control.feedback(1, c * plant), w)
    assert lm.ms(PidGains(kp=1.2, tn=120.0, tv=20.0, td=5.0)) == pytest.approx(
        float(np.max(np.abs(resp.magnitude))), rel=1e-6
    )


def test_simc_and_amigo_follow_the_reference_formulas():
    fit = FopdtFit(gain=0.5916, time_constant_s=23.4, dead_time_s=10.6)
    s = simc(fit)
    assert s.kp == pytest.approx(23.4 / (0.5916 * 21.2)) and s.tn == pytest.approx(23.4) and s.tv == 0.0
    a = amigo(fit)
    assert a.kp * 0.5916 == pytest.approx(0.2 + 0.45 * 23.4 / 10.6)
    assert a.tn == pytest.approx(10.6 * (0.4 * 10.6 + 0.8 * 23.4) / (10.6 + 2.34))
    assert a.tv == pytest.approx(0.5 * 10.6 * 23.4 / (0.3 * 10.6 + 23.4))


def test_operating_point_and_fit_of_a_nonlinear_plant():
    sc = load_scenario(resolve_scenario("t6_nonlinear_hotend"))
    assert operating_point(sc) == (150.0, 250.0)
    assert operating_point(load_scenario(resolve_scenario("seed003_hotend_fuzzy"))) == (160.0, 200.0)
    lm = loop_model(sc)
    # loss k·ΔT^1.35 = P·u: the local gain dΔT/du is ΔT/(1.35·u) at the holding power u
    from modbus_bridge.optimise.robustness import plant_model
    from modbus_bridge.plants.response import rest_input

    u = rest_input(plant_model(sc), 250.0)
    assert lm.fit.gain == pytest.approx(225.0 / (1.35 * u), rel=0.03)
    assert lm.fit.dead_time_s > 5.0  # the 5.5 s input dead time (+ nothing else: one lump)


@pytest.mark.parametrize(("name", "phase"), [("t2_rrf_bed", "draught"), ("t3_marlin_hotend", "fan"),
                                             ("seed004_cure_mould", "ramp"), ("t6_nonlinear_hotend", "up")])
def test_the_scored_window_starts_at_the_test_not_at_the_hand_over_from_tune(name: str, phase: str) -> None:
    """Without a setpoint step the window starts at the first load or ramp: a fixed set starts its hold at
    rest on W, the self-tuned one 20 % short of it, and that settling is not the test."""
    from modbus_bridge.optimise.robustness import scored_step

    sc = load_scenario(resolve_scenario(name))
    assert sc.zones[0].phases[scored_step(sc)[0]].name == phase


def test_a_zone_tuned_on_its_cooling_side_gets_a_fixed_set_in_its_cooling_registers() -> None:
    """Seed 000 tunes the platform's cooling set and steps it down: a set written to the heating registers
    would leave that step on the cooling defaults, every fixed set alike."""
    from modbus_bridge.optimise.experiment import PidGains, fixed_gain_scenario, tunes_cooling

    gains = PidGains(kp=12.0, tn=300.0, tv=20.0, td=5.0)
    cooled = load_scenario(resolve_scenario("seed000_forming_platform"))
    heated = load_scenario(resolve_scenario("seed003_hotend_fuzzy"))
    assert tunes_cooling(cooled.zones[0]) and not tunes_cooling(heated.zones[0])
    writes = fixed_gain_scenario(cooled, gains, 100.0).zones[0].phases[0].writes
    assert {k: writes[k] for k in ("fKpCoolZone2", "fTnCoolZone2", "fTvCoolZone2", "fTdCoolZone2")} == {
        "fKpCoolZone2": 12.0, "fTnCoolZone2": 300.0, "fTvCoolZone2": 20.0, "fTdCoolZone2": 5.0}
    assert "fKpZone2" not in writes
    assert fixed_gain_scenario(heated, gains, 100.0).zones[0].phases[0].writes["fKpZone1"] == 12.0
