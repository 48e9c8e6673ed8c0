"""Plant models: exact discretisation against closed forms, saturation, dead time, physics checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from modbus_bridge.plants import (
    CureMould,
    DelayLine,
    Fopdt,
    FormingPlatform,
    MarlinHotend,
    NonlinearHotend,
    PlantDisturbance,
    Sopdt,
    TclabTwin,
)
from modbus_bridge.plants.base import rk4_step

DT = 0.1


def run(plant, u, seconds, dt=DT, dist=None):
    dist = dist or PlantDisturbance.for_channels(plant.channels)
    ys = []
    for _ in range(round(seconds / dt)):
        plant.step(u, dt, dist)
        ys.append(plant.temperatures())
    return np.array(ys)


def test_fopdt_matches_closed_form_step_response():
    k, tau, lag, amb, u = 0.232, 23.4, 10.6, 160.0, 40.0
    p = Fopdt(gain_c_per_pct=k, time_constant_s=tau, dead_time_s=lag, ambient_c=amb)
    y = run(p, [u], 120.0)[:, 0]
    t = DT * np.arange(1, y.size + 1)
    # the input applied during step k acts from t_k - dt; with the delay the response starts at L
    expected = amb + k * u * np.where(t > lag, 1.0 - np.exp(-(t - lag) / tau), 0.0)
    assert np.max(np.abs(y - expected)) < 1e-9


def test_fopdt_fractional_dead_time_is_honoured():
    p = Fopdt(gain_c_per_pct=1.0, time_constant_s=194.8, dead_time_s=1.05, ambient_c=0.0)
    y = run(p, [100.0], 3.0)[:, 0]
    t = DT * np.arange(1, y.size + 1)
    assert np.all(y[t <= 1.0 + 1e-9] == 0.0)  # nothing before the dead time
    assert y[int(round(1.1 / DT)) - 1] > 0.0  # something after it
    exact = 100.0 * (1.0 - np.exp(-(t - 1.05) / 194.8))
    assert np.max(np.abs(y[t > 1.2] - exact[t > 1.2])) < 0.01


def test_sopdt_matches_closed_form():
    k, t1, t2 = 2.0, 30.0, 8.0
    p = Sopdt(gain_c_per_pct=k, time_constant_s=t1, time_constant2_s=t2, dead_time_s=0.0, ambient_c=0.0)
    y = run(p, [10.0], 100.0)[:, 0]
    t = DT * np.arange(1, y.size + 1)
    expected = 20.0 * (1.0 - (t1 * np.exp(-t / t1) - t2 * np.exp(-t / t2)) / (t1 - t2))
    assert np.max(np.abs(y - expected)) < 1e-9


def test_model_mismatch_scales_the_time_constant():
    base = Fopdt(gain_c_per_pct=1.0, time_constant_s=20.0, dead_time_s=0.0, ambient_c=0.0)
    slow = Fopdt(
        gain_c_per_pct=1.0, time_constant_s=20.0, dead_time_s=0.0, ambient_c=0.0, time_constant_scale=1.5
    )
    yb, ys = run(base, [100.0], 30.0)[:, 0], run(slow, [100.0], 30.0)[:, 0]
    assert yb[round(20.0 / DT) - 1] == pytest.approx(100.0 * (1 - math.exp(-1)), rel=1e-9)
    assert ys[round(30.0 / DT) - 1] == pytest.approx(100.0 * (1 - math.exp(-1)), rel=1e-9)


def test_heater_saturation_and_nan_command():
    a = Fopdt(gain_c_per_pct=1.0, time_constant_s=5.0, dead_time_s=0.0, ambient_c=20.0)
    b = Fopdt(gain_c_per_pct=1.0, time_constant_s=5.0, dead_time_s=0.0, ambient_c=20.0)
    assert np.array_equal(run(a, [250.0], 10.0), run(b, [100.0], 10.0))
    c = Fopdt(gain_c_per_pct=1.0, time_constant_s=5.0, dead_time_s=0.0, ambient_c=20.0)
    assert np.all(run(c, [float("nan")], 5.0) == 20.0)
    d = Fopdt(gain_c_per_pct=1.0, time_constant_s=5.0, dead_time_s=0.0, ambient_c=20.0)
    assert np.all(run(d, [-50.0], 5.0) == 20.0)  # heater only: no cooling


def test_load_and_heater_failure_and_ambient_step():
    p = Fopdt(gain_c_per_pct=1.0, time_constant_s=5.0, dead_time_s=0.0, ambient_c=20.0)
    dist = PlantDisturbance.for_channels(1)
    dist.zones[0].load_pct = 10.0
    y = run(p, [50.0], 100.0, dist=dist)[-1, 0]
    assert y == pytest.approx(20.0 + 40.0, abs=1e-6)
    dist.zones[0].heater_failed = True
    dist.ambient_offset_c = 5.0
    y = run(p, [50.0], 200.0, dist=dist)[-1, 0]
    assert y == pytest.approx(25.0 - 10.0, abs=1e-6)  # failed heater, load still drains 10 %


def test_delay_line_integer_delay_is_exact():
    line = DelayLine(0.3, 0.1)
    out = [line.push(v) for v in [1.0, 2.0, 3.0, 4.0, 5.0]]
    assert out == [0.0, 0.0, 0.0, 1.0, 2.0]


def test_rk4_is_fourth_order_on_exponential_decay():
    x = np.array([1.0])
    x = rk4_step(lambda s: -s, x, 1.0, 0.1)
    assert abs(x[0] - math.exp(-1.0)) < 1e-6


def test_nonlinear_hotend_steady_state_and_falling_gain():
    p = NonlinearHotend(dead_time_s=0.0, ambient_c=25.0)
    y_full = run(p, [100.0], 4000.0, dt=1.0)[-1, 0]
    assert y_full - 25.0 == pytest.approx(340.0, rel=1e-3)  # max_rise_c at 100 %
    low = NonlinearHotend(dead_time_s=0.0, ambient_c=25.0)
    y_half = run(low, [50.0], 4000.0, dt=1.0)[-1, 0]
    # loss ~ dT^1.35: half the power gives (1/2)^(1/1.35) of the rise, more than a linear plant's half
    assert (y_half - 25.0) / 340.0 == pytest.approx(0.5 ** (1 / 1.35), rel=1e-3)


def test_nonlinear_hotend_fan_and_filament_cool_it():
    ref = run(NonlinearHotend(dead_time_s=0.0), [60.0], 2000.0, dt=1.0)[-1, 0]
    dist = PlantDisturbance.for_channels(1)
    dist.zones[0].fan = 1.0
    dist.zones[0].filament_mm_s = 5.0
    cooled = run(NonlinearHotend(dead_time_s=0.0), [60.0], 2000.0, dt=1.0, dist=dist)[-1, 0]
    assert cooled < ref - 5.0


def test_marlin_hotend_steady_state_and_sensor_lag():
    p = MarlinHotend(ambient_c=25.0)
    y = run(p, [50.0], 3000.0, dt=1.0)[-1, 0]
    assert y - 25.0 == pytest.approx(20.0 / 0.068, rel=1e-3)
    q = MarlinHotend(ambient_c=25.0)
    q.step([100.0], 5.0, PlantDisturbance.for_channels(1))
    block, sensor = q._x
    assert block > sensor > 25.0


def test_tclab_steady_state_matches_equations():
    p = TclabTwin()
    y = run(p, [50.0, 50.0], 3000.0, dt=1.0)[-1]
    expected = 21.0 + 20.0 * 200.0 * 50.0 / 5720.0  # symmetric heating: no cross flow
    assert y[0] == pytest.approx(expected, rel=1e-4)
    assert y[1] == pytest.approx(expected, rel=1e-4)
    asym = run(TclabTwin(), [80.0, 0.0], 3000.0, dt=1.0)[-1]
    assert asym[0] > asym[1] > 21.0  # heater 1 warms sensor 2 through the coupling


def test_forming_platform_cools_below_ambient_with_split_output():
    p = FormingPlatform(ambient_c=20.0, max_substep_s=5.0)
    y = run(p, [-100.0], 20000.0, dt=10.0)[-1, 0]
    # steady state of the two-node network with 60 W extracted from the bath
    g_ba, g_bp, g_pa = 1.0, 5.0, 0.3
    a = np.array([[g_ba + g_bp, -g_bp], [-g_bp, g_bp + g_pa]])
    bath, plat = np.linalg.solve(a, np.array([-60.0 + g_ba * 20.0, g_pa * 20.0]))
    assert y == pytest.approx(plat, abs=1e-3)
    assert y < 20.0


def test_cure_mould_exotherm_and_mesh_coupling():
    hot = CureMould(initial_c=150.0)
    cold = CureMould(initial_c=150.0, cure_enthalpy_j=0.0)
    u = [60.0, 60.0, 60.0, 60.0]
    y_hot = run(hot, u, 600.0, dt=1.0)[-1]
    y_cold = run(cold, u, 600.0, dt=1.0)[-1]
    assert np.all(y_hot > y_cold + 1.0)  # cure heat once above the activation temperature
    assert min(hot.degree_of_cure()) > 0.1
    below = CureMould(initial_c=100.0)
    run(below, [0.0] * 4, 600.0, dt=1.0)
    assert max(below.degree_of_cure()) == 0.0  # no cure below the activation temperature
    one = CureMould(initial_c=80.0, cure_enthalpy_j=0.0)
    y = run(one, [100.0, 0.0, 0.0, 0.0], 2000.0, dt=1.0)[-1]
    assert y[1] == pytest.approx(y[2])
    assert y[0] > y[1] > y[3] > 80.0  # neighbours warm first, the diagonal last


def test_bench_measures_every_plant_model():
    from modbus_bridge.bench import plant_costs
    from modbus_bridge.plants import PLANT_MODELS

    costs = plant_costs(20)
    assert set(costs) == set(PLANT_MODELS)
    assert all(us > 0.0 for us in costs.values())
