"""Sensors: PT100 Callendar–Van Dusen, NTC β, ADC quantisation, lag, seeded noise, faults."""

from __future__ import annotations

import math

import pytest

from modbus_bridge.sensors import (
    AdcFrontEnd,
    Sensor,
    ntc_resistance,
    ntc_temperature,
    pt100_resistance,
    pt100_temperature,
)


@pytest.mark.parametrize(
    ("temp", "ohm"), [(0.0, 100.0), (100.0, 138.5055), (-100.0, 60.2558), (850.0, 390.4811)]
)
def test_pt100_iec60751_table_values(temp, ohm):
    assert pt100_resistance(temp) == pytest.approx(ohm, abs=1e-3)
    assert pt100_temperature(pt100_resistance(temp)) == pytest.approx(temp, abs=1e-6)


def test_ntc_beta_equation_roundtrip():
    assert ntc_resistance(25.0, 100_000.0, 3950.0) == pytest.approx(100_000.0)
    r = ntc_resistance(200.0, 100_000.0, 3950.0)
    assert r < 1000.0
    assert ntc_temperature(r, 100_000.0, 3950.0) == pytest.approx(200.0, abs=1e-9)


def test_adc_quantisation_step_size():
    adc = AdcFrontEnd(kind="ntc", bits=12)
    values = {adc.from_counts(adc.to_counts(200.0 + 0.01 * i)) for i in range(100)}
    steps = sorted(values)
    gaps = [b - a for a, b in zip(steps, steps[1:], strict=False)]
    assert len(steps) > 1
    assert all(0.05 < g < 0.3 for g in gaps)  # about 0.12 °C per count at 200 °C with 4.7 kΩ pull-up


def test_sensor_lag_and_seeded_noise():
    s = Sensor(lag_s=2.0)
    s.reset(20.0)
    v = s.measure(30.0, 2.0)
    assert v == pytest.approx(20.0 + 10.0 * (1 - math.exp(-1)))
    a = [Sensor(noise_sigma_c=0.2, seed=5).measure(100.0, 0.1) for _ in range(3)]
    assert a[0] == a[1] == a[2] != 100.0
    b = Sensor(noise_sigma_c=0.2, seed=6).measure(100.0, 0.1)
    assert b != a[0]


def test_sensor_faults_read_out_of_range():
    for kind in ("pt100", "ntc"):
        s = Sensor(adc=AdcFrontEnd(kind=kind))
        s.measure(100.0, 0.1)
        s.fault = "open"
        open_value = s.measure(100.0, 0.1)
        s.fault = "short"
        short_value = s.measure(100.0, 0.1)
        assert abs(open_value - 100.0) > 150.0 and abs(short_value - 100.0) > 150.0
    plain = Sensor()
    plain.fault = "open"
    assert plain.measure(50.0, 0.1) < -200.0


def _longest_unchanged_run(sensor: Sensor, temp_c: float, samples: int) -> int:
    longest = run = 0
    last = None
    for _ in range(samples):
        v = sensor.measure(temp_c, 0.1)
        run = run + 1 if v == last else 0
        longest = max(longest, run)
        last = v
    return longest


def test_converter_noise_keeps_a_quiet_reading_alive():
    """A constant temperature at the centre of a code (as far from both transitions as it gets), sensor
    noise 1/6 LSB (seed 003's hot end): the converter's own transition noise makes the reading move well
    within the frozen-PV time (28 s = 280 samples), as a real input card's does; without it the reading
    stays bit-identical longer than that, which the protection would rightly call frozen."""
    frozen_samples = 280
    adc = AdcFrontEnd(kind="ntc", bits=12)
    code_centre = adc.from_counts(adc.to_counts(200.0))
    real = Sensor(noise_sigma_c=0.02, adc=AdcFrontEnd(kind="ntc", bits=12), seed=1)
    assert _longest_unchanged_run(real, code_centre, 20 * frozen_samples) < frozen_samples // 4
    silent = Sensor(noise_sigma_c=0.02, adc=AdcFrontEnd(kind="ntc", bits=12, noise_lsb=0.0), seed=1)
    assert _longest_unchanged_run(silent, code_centre, 20 * frozen_samples) >= frozen_samples
