"""Detection bound of the fault bench: the open-loop departure after an actuator fault, checked against the
FOPDT step response K dY (1 - exp(-(t - L) / T)) of seed 003's hot end."""

from __future__ import annotations

import math

import pytest

from modbus_bridge.faults import open_loop_departure

K, T, L = 0.5916, 23.4, 10.6  # seed003_hotend_fuzzy.toml
Y0 = 67.6


@pytest.mark.parametrize(("fault", "delta_y"), [("heater_open", -Y0), ("heater_weak", -0.7 * Y0),
                                                ("stuck_on", 100.0 - Y0)])
def test_departure_is_the_fopdt_step_response(fault, delta_y):
    after = L + 5.0
    expected = K * delta_y * (1.0 - math.exp(-(after - L) / T))
    got = open_loop_departure("seed003_hotend_fuzzy", fault, Y0, after, rest_s=2000.0)
    assert got == pytest.approx(expected, rel=0.02)


def test_no_departure_within_the_dead_time():
    assert abs(open_loop_departure("seed003_hotend_fuzzy", "heater_open", Y0, L - 0.5, rest_s=500.0)) < 1e-9


def test_sensor_faults_have_no_actuator_bound():
    with pytest.raises(ValueError, match="not an actuator fault"):
        open_loop_departure("seed003_hotend_fuzzy", "frozen_pv", Y0, 5.0)
