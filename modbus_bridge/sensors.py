"""Temperature sensors and their analog front end: PT100 (Callendar–Van Dusen) and NTC (β equation).

A sensor turns the true temperature at the sensor into what the PLC sees:
first-order sensor lag, seeded Gaussian noise, then the raw ADC path (resistance -> counts,
quantised) and back to °C, so ADC quantisation shows in the process value exactly as it would
through a real input card. `raw_counts` is what the "raw input" path of the application receives.

Sources: IEC 60751 (ITS-90 PT100 coefficients A, B, C: the simulated sensor is a standard one; seed 000
quotes the older 3.90802e-3 / -5.80195e-7 / -4.2735e-12 set, which the library uses, so a raw-path PLC
reads 0.04 °C high at 200 °C and 0.75 °C at 850 °C, as a real mismatched calibration would); seed 002
(100 kΩ NTC hot end);
the β equation 1/T = 1/T0 + ln(R/R0)/β.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

KELVIN_OFFSET = 273.15
# what a sensor with no raw path reads when detached (open) or shorted (an NTC-like behaviour)
OPEN_READING_C = -KELVIN_OFFSET
SHORT_READING_C = 1000.0
SENSOR_FAULTS = ("none", "open", "short")

# IEC 60751 (ITS-90) Callendar–Van Dusen coefficients.
CVD_A = 3.9083e-3
CVD_B = -5.775e-7
CVD_C = -4.183e-12
PT100_R0_OHM = 100.0
PT100_RANGE_C = (-200.0, 850.0)
DEFAULT_ADC_NOISE_LSB = 0.3


def pt100_resistance(temp_c: float, r0_ohm: float = PT100_R0_OHM) -> float:
    """Callendar–Van Dusen: R(T) = R0(1 + A T + B T^2 + C (T - 100) T^3), C term only below 0 °C."""
    t = temp_c
    cubic = CVD_C * (t - 100.0) * t**3 if t < 0.0 else 0.0
    return r0_ohm * (1.0 + CVD_A * t + CVD_B * t * t + cubic)


def pt100_temperature(resistance_ohm: float, r0_ohm: float = PT100_R0_OHM) -> float:
    """Inverse CVD: closed form above 0 °C, Newton iterations below."""
    ratio = resistance_ohm / r0_ohm
    if ratio >= 1.0:
        disc = CVD_A * CVD_A - 4.0 * CVD_B * (1.0 - ratio)
        if disc < 0.0:  # beyond the parabola's vertex (open sensor): linear, clearly out of range
            return (ratio - 1.0) / CVD_A
        return (-CVD_A + math.sqrt(disc)) / (2.0 * CVD_B)
    t = (ratio - 1.0) / CVD_A
    for _ in range(20):
        f = pt100_resistance(t, r0_ohm) - resistance_ohm
        slope = r0_ohm * (CVD_A + 2 * CVD_B * t + CVD_C * (4 * t**3 - 300 * t * t))
        step = f / slope
        t -= step
        if abs(step) < 1e-9:
            break
    return t


def ntc_resistance(temp_c: float, r25_ohm: float, beta_k: float, t0_c: float = 25.0) -> float:
    """β equation: R(T) = R0 exp(β (1/T - 1/T0)), T in kelvin."""
    t_k = temp_c + KELVIN_OFFSET
    t0_k = t0_c + KELVIN_OFFSET
    return r25_ohm * math.exp(beta_k * (1.0 / t_k - 1.0 / t0_k))


def ntc_temperature(resistance_ohm: float, r25_ohm: float, beta_k: float, t0_c: float = 25.0) -> float:
    t0_k = t0_c + KELVIN_OFFSET
    inv = 1.0 / t0_k + math.log(resistance_ohm / r25_ohm) / beta_k
    if inv <= 0.0:  # a (near) short circuit: beyond any physical temperature
        return SHORT_READING_C
    return min(1.0 / inv - KELVIN_OFFSET, SHORT_READING_C)


@dataclass
class AdcFrontEnd:
    """Raw input path. kind "pt100": counts = (R - ohm_at_zero) / ohm_per_count (a resistance-measuring
    input card, e.g. 1/16 Ω per count). kind "ntc": a pull-up divider read by an ADC,
    counts = full * R/(R+Rpull). kind "none": no quantisation (the PV is written as REAL as measured)."""

    kind: str = "none"
    bits: int = 16
    ohm_per_count: float = 1.0 / 16.0
    ohm_at_zero: float = 0.0  # pt100: resistance at count 0 (an input card with an offset range)
    pullup_ohm: float = 4700.0
    r25_ohm: float = 100_000.0
    beta_k: float = 3950.0
    # the converter's own transition noise, LSB rms, before rounding: SAR converters of 12 to 16 bits state
    # 0.3 to 1 LSB; without it a quiet reading between two codes would stay bit-identical for minutes,
    # which no real input card does (and which the frozen-PV protection rightly calls a fault)
    noise_lsb: float = DEFAULT_ADC_NOISE_LSB

    @property
    def full_scale(self) -> int:
        return (1 << self.bits) - 1

    def to_counts(self, temp_c: float, noise_lsb: float = 0.0) -> int:
        """The code the converter returns for temp_c, with noise_lsb (LSB) added before rounding."""
        if self.kind == "pt100":
            exact = (pt100_resistance(temp_c) - self.ohm_at_zero) / self.ohm_per_count
        elif self.kind == "ntc":
            r = ntc_resistance(temp_c, self.r25_ohm, self.beta_k)
            exact = self.full_scale * r / (r + self.pullup_ohm)
        else:
            raise ValueError("front end 'none' has no raw counts")
        return int(min(max(round(exact + noise_lsb), 0), self.full_scale))

    def from_counts(self, counts: int) -> float:
        if self.kind == "pt100":
            return pt100_temperature(self.ohm_at_zero + counts * self.ohm_per_count)
        if self.kind == "ntc":
            c = min(max(counts, 1), self.full_scale - 1)
            r = self.pullup_ohm * c / (self.full_scale - c)
            return ntc_temperature(r, self.r25_ohm, self.beta_k)
        raise ValueError("front end 'none' has no raw counts")


@dataclass
class Sensor:
    """Sensor lag (first order, exact discretisation), seeded noise, ADC quantisation."""

    lag_s: float = 0.0
    noise_sigma_c: float = 0.0
    adc: AdcFrontEnd = field(default_factory=AdcFrontEnd)
    seed: int = 0
    offset_c: float = 0.0
    fault: str = "none"
    _state: float | None = field(default=None, init=False, repr=False)
    _rng: np.random.Generator = field(init=False, repr=False)
    last_counts: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng(self.seed)

    def reset(self, temp_c: float) -> None:
        self._state = temp_c

    def measure(self, true_temp_c: float, dt: float) -> float:
        """Advance the sensor by dt and return the temperature the PLC sees."""
        if self._state is None:
            self._state = true_temp_c
        if self.lag_s > 0.0:
            alpha = math.exp(-dt / self.lag_s)
            self._state = alpha * self._state + (1.0 - alpha) * true_temp_c
        else:
            self._state = true_temp_c
        if self.fault != "none":
            return self._faulted()
        value = self._state + self.offset_c
        if self.noise_sigma_c > 0.0:
            value += float(self._rng.normal(0.0, self.noise_sigma_c))
        if self.adc.kind != "none":
            dither = float(self._rng.normal(0.0, self.adc.noise_lsb)) if self.adc.noise_lsb > 0.0 else 0.0
            self.last_counts = self.adc.to_counts(value, dither)
            return self.adc.from_counts(self.last_counts)
        return value

    def _faulted(self) -> float:
        """Open or shorted sensor: the raw value goes to the end of the ADC range."""
        if self.adc.kind == "none":
            return OPEN_READING_C if self.fault == "open" else SHORT_READING_C
        # open RTD reads full scale (very hot), shorted 0; an NTC with pull-up: open reads full scale
        # (very cold), shorted 0 (very hot)
        self.last_counts = self.adc.full_scale if self.fault == "open" else 0
        return self.adc.from_counts(self.last_counts)
