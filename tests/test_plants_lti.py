"""n-lag and transfer-function plants: exact ZOH discretisation against closed forms and against an
independent simulation (python-control), the FOPDT as a special case, scenario loading and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from modbus_bridge.plants import Fopdt, NLag, PlantDisturbance, TransferFunctionPlant
from modbus_bridge.scenario import ScenarioError, load_scenario, resolve_scenario

DT = 0.1


def run(plant, u, seconds, dt=DT, dist=None, events=None):
    dist = dist or PlantDisturbance.for_channels(plant.channels)
    ys = []
    for k in range(round(seconds / dt)):
        if events and k in events:
            events[k](plant, dist)
        plant.step([u], dt, dist)
        ys.append(plant.temperatures()[0])
    return np.array(ys)


def test_nlag_matches_the_closed_form_step_response():
    k, tau, n, lag, amb, u = 0.8, 12.0, 3, 2.0, 25.0, 50.0
    y = run(NLag(gain_c_per_pct=k, time_constant_s=tau, order=n, dead_time_s=lag, ambient_c=amb), u, 150.0)
    t = DT * np.arange(1, y.size + 1)
    s = np.clip(t - lag, 0.0, None) / tau
    # K u (1 - e^(-t/T) sum_{i<n} (t/T)^i / i!)
    expected = amb + k * u * (1.0 - np.exp(-s) * sum(s**i / math.factorial(i) for i in range(n)))
    assert np.max(np.abs(y - expected)) < 1e-9


def test_transfer_function_with_a_zero_matches_partial_fractions():
    a, t1, t2 = 5.0, 30.0, 8.0  # (a s + 1) / ((t1 s + 1)(t2 s + 1))
    den = np.polymul([t1, 1.0], [t2, 1.0])
    y = run(TransferFunctionPlant(num=(a, 1.0), den=tuple(den), ambient_c=0.0), 10.0, 120.0)
    t = DT * np.arange(1, y.size + 1)
    expected = 10.0 * (1.0 - (t1 - a) / (t1 - t2) * np.exp(-t / t1) - (t2 - a) / (t2 - t1) * np.exp(-t / t2))
    assert np.max(np.abs(y - expected)) < 1e-9


def test_fourth_order_with_complex_poles_matches_python_control():
    control = pytest.importorskip("control", reason="python-control (dev dependency) is the oracle")
    num = (0.4, 2.0)
    den = tuple(np.polymul(np.polymul([50.0, 1.0], [4.0, 1.0]), [25.0, 4.0, 1.0]))  # zeta = 0.4
    lag = 1.5
    y = run(TransferFunctionPlant(num=num, den=den, dead_time_s=lag, ambient_c=0.0), 20.0, 200.0)
    t = DT * np.arange(0, y.size + 1)
    resp = control.forced_response(control.tf(list(num), list(den)), T=t, U=np.full(t.size, 20.0))
    ref = np.interp(DT * np.arange(1, y.size + 1) - lag, t, resp.outputs, left=0.0)
    assert np.max(np.abs(y - ref)) < 1e-6 * np.max(np.abs(ref))


def test_first_order_transfer_function_is_the_fopdt_with_disturbances_and_mismatch():
    k, tau, lag = 0.5916, 23.4, 10.6

    def events():
        return {
            100: lambda p, d: setattr(d.zones[0], "load_pct", 3.0),
            400: lambda p, d: setattr(d, "ambient_offset_c", -2.0),
            700: lambda p, d: setattr(p, "time_constant_scale", 1.3),
        }

    fo = Fopdt(gain_c_per_pct=k, time_constant_s=tau, dead_time_s=lag, ambient_c=160.0, initial_c=170.0)
    tf = TransferFunctionPlant(num=(k,), den=(tau, 1.0), dead_time_s=lag, ambient_c=160.0, initial_c=170.0)
    y_fo = run(fo, 60.0, 120.0, events=events())
    y_tf = run(tf, 60.0, 120.0, events=events())
    assert y_tf[0] == pytest.approx(170.0, abs=1e-9)  # starts at rest off ambient
    assert np.max(np.abs(y_fo - y_tf)) < 1e-9


def test_saturation_nan_and_failed_heater():
    p = NLag(gain_c_per_pct=1.0, time_constant_s=5.0, order=2, ambient_c=20.0)
    assert run(p, 500.0, 200.0)[-1] == pytest.approx(120.0, abs=1e-6)  # 100 % at most
    p.reset()
    assert run(p, math.nan, 10.0)[-1] == pytest.approx(20.0)
    dist = PlantDisturbance.for_channels(1)
    dist.zones[0].heater_failed = True
    p.reset()
    assert run(p, 80.0, 10.0, dist=dist)[-1] == pytest.approx(20.0)


@pytest.mark.parametrize(
    ("kwargs", "why"),
    [
        ({"num": (1.0, 0.0, 1.0), "den": (5.0, 1.0)}, "improper"),
        ({"num": (1.0,), "den": (-5.0, 1.0)}, "unstable"),
        ({"num": (1.0,), "den": (5.0, 0.0)}, "root at s = 0"),
        ({"num": (0.0,), "den": (5.0, 1.0)}, "all zeros"),
        ({"num": (1.0,), "den": (2.0,)}, "degree >= 1"),
    ],
)
def test_bad_transfer_functions_are_refused(kwargs, why):
    with pytest.raises(ValueError, match=why):
        TransferFunctionPlant(**kwargs)


def test_nlag_order_must_be_whole():
    with pytest.raises(ValueError, match="whole number"):
        NLag(gain_c_per_pct=1.0, time_constant_s=5.0, order=2.5)


SCENARIO = """
name = "tf"
description = "user model"
[plant]
model = "transfer_function"
{plant}
[[zone]]
name = "z"
plc_zone = 1
[[zone.phase]]
name = "hold"
mode = "ACTIVE"
setpoint_c = 50.0
duration_s = 10.0
"""


def test_scenario_with_a_transfer_function_builds_the_plant(tmp_path):
    path = tmp_path / "tf.toml"
    path.write_text(SCENARIO.format(plant="num = [2.0]\nden = [100.0, 25.0, 1]\ndead_time_s = 3.0"))
    sc = load_scenario(path)
    plant = sc.build_plant()
    assert isinstance(plant, TransferFunctionPlant)
    assert plant.den == (100.0, 25.0, 1.0) and plant.dc_gain == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("plant", "key", "why"),
    [
        ('num = "2"\nden = [10.0, 1.0]', "plant.num", "list of finite numbers"),
        ("num = [2.0]\nden = []", "plant.den", "list of finite numbers"),
        ("num = [2.0]\nden = [10.0, true]", "plant.den", "list of finite numbers"),
        ("num = [2.0]\nden = [-10.0, 1.0]", "plant", "unstable"),
        ("num = [2.0]", "plant.den", "missing required field"),
    ],
)
def test_bad_transfer_function_in_a_scenario_names_key_and_reason(tmp_path, plant, key, why):
    path = tmp_path / "bad.toml"
    path.write_text(SCENARIO.format(plant=plant))
    with pytest.raises(ScenarioError, match=f"{key}: .*{why}"):
        load_scenario(path)


def test_shipped_nlag_scenario_loads():
    sc = load_scenario(resolve_scenario("nlag_oven"))
    assert sc.plant_model == "nlag" and sc.build_plant().order == 4
