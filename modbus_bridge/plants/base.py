"""Common pieces of every plant: the disturbance state, heater saturation, the dead-time delay line.

Integrators (documented per plant):
- linear plants (FOPDT, SOPDT) use the exact zero-order-hold discretisation of each first-order lag,
  x[k+1] = a x[k] + (1 - a) K u[k], a = exp(-dt/T): exact for a piecewise-constant input;
- nonlinear plants use fixed-step classic RK4 with sub-steps no longer than `max_substep_s`;
- dead time is a delay line on the heater input (sample-and-hold buffer of past inputs, linear
  interpolation for the fraction of a step), so a delay that is not a multiple of dt is still honoured.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

State = np.ndarray
Derivative = Callable[[State], State]


@dataclass
class ZoneDisturbance:
    """Disturbances acting on one plant channel; the scenario runner changes them over time."""

    load_pct: float = 0.0  # extra heat loss in % of full heater power, input side (via dead time)
    heater_failed: bool = False  # open heater: the command has no effect
    fan: float = 0.0  # part-cooling fan duty 0..1 (plants with a fan term)
    filament_mm_s: float = 0.0  # filament feed rate (hot ends with a filament term)


@dataclass
class PlantDisturbance:
    ambient_offset_c: float = 0.0
    zones: list[ZoneDisturbance] = field(default_factory=list)

    @staticmethod
    def for_channels(n: int) -> PlantDisturbance:
        return PlantDisturbance(zones=[ZoneDisturbance() for _ in range(n)])


def saturate(value: float, low: float, high: float) -> float:
    if math.isnan(value):  # a NaN command is treated as "off"
        return min(max(0.0, low), high)
    return min(max(value, low), high)


class DelayLine:
    """Pure dead time of `delay_s` for a signal sampled every `dt` (zero-order hold between samples)."""

    def __init__(self, delay_s: float, dt: float, initial: float = 0.0) -> None:
        if delay_s < 0.0 or dt <= 0.0:
            raise ValueError("delay must be >= 0 and dt > 0")
        steps = round(delay_s / dt, 9)  # 0.3/0.1 is 2.9999999999999996 in binary floating point
        self._whole = int(math.floor(steps))
        self._frac = steps - self._whole
        self._buffer: deque[float] = deque([initial] * (self._whole + 2), maxlen=self._whole + 2)

    def resized(self, delay_s: float, dt: float) -> DelayLine:
        """A line of the new delay keeping this line's recent inputs (the oldest repeated when it grows)."""
        line = DelayLine(delay_s, dt, initial=self._buffer[0])
        for value in self._buffer:
            line._buffer.append(value)
        return line

    def push(self, value: float) -> float:
        """Push the newest input; return the input as seen `delay_s` later (interpolated)."""
        self._buffer.append(value)
        newer = self._buffer[-1 - self._whole]
        older = self._buffer[-2 - self._whole]
        return (1.0 - self._frac) * newer + self._frac * older


def rk4_step(f: Derivative, x: State, dt: float, max_substep_s: float) -> State:
    """Classic fixed-step Runge–Kutta 4 over dt, split into equal sub-steps <= max_substep_s."""
    n = max(1, math.ceil(dt / max_substep_s - 1e-12))
    h = dt / n
    for _ in range(n):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


class Plant:
    """Interface every plant implements. Inputs are controller outputs in % (heat > 0, cool < 0);
    `temperatures()` are the true temperatures at the sensor positions, one per channel."""

    channels: int = 1
    u_min_pct: float = 0.0
    u_max_pct: float = 100.0

    def reset(self) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:  # pragma: no cover
        raise NotImplementedError

    def temperatures(self) -> list[float]:  # pragma: no cover - interface
        raise NotImplementedError

    def effective_inputs(self, u_pct: Sequence[float], dist: PlantDisturbance) -> list[float]:
        """Saturate, cut failed heaters, subtract the load (in % of full power)."""
        out = []
        for i in range(self.channels):
            u = saturate(float(u_pct[i]), self.u_min_pct, self.u_max_pct)
            zd = dist.zones[i] if i < len(dist.zones) else ZoneDisturbance()
            if zd.heater_failed:
                u = 0.0
            out.append(u - zd.load_pct)
        return out
