"""Linear first- and second-order plus dead time plants (FOPDT, SOPDT).

G(s) = K e^(-L s) / (T s + 1)  and  K e^(-L s) / ((T1 s + 1)(T2 s + 1)), input in % of heater power,
output the temperature; ambient enters through the same lags (dT/dt = (Ta + K u(t - L) - T)/T).
Integrator: exact zero-order-hold discretisation (see base.py); dead time: DelayLine.

Sources: seed 003 (hot end G(s) = 0.232 e^(-10.6 s)/(23.4 s + 1)); seed 002 (ZN data T = 194.8, L = 1.05);
reference/control.md T1, T2 (RepRapFirmware defaults) and T4's identified FOPDT.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from .base import DelayLine, Plant, PlantDisturbance


@dataclass
class Fopdt(Plant):
    gain_c_per_pct: float
    time_constant_s: float
    dead_time_s: float
    ambient_c: float = 25.0
    initial_c: float | None = None
    time_constant_scale: float = 1.0  # model mismatch: the real plant is slower (1.3, 1.5) than identified
    gain_scale: float = 1.0
    u_min_pct: float = 0.0
    u_max_pct: float = 100.0
    channels: int = field(default=1, init=False)

    def __post_init__(self) -> None:
        if self.time_constant_s <= 0.0 or self.dead_time_s < 0.0:
            raise ValueError("time constant must be > 0 and dead time >= 0")
        if self.u_min_pct >= self.u_max_pct:
            raise ValueError(f"actuator range u_min_pct {self.u_min_pct} >= u_max_pct {self.u_max_pct}")
        self.reset()

    @property
    def true_gain(self) -> float:
        return self.gain_c_per_pct * self.gain_scale

    @property
    def true_time_constant(self) -> float:
        return self.time_constant_s * self.time_constant_scale

    def reset(self) -> None:
        self._temp = self.ambient_c if self.initial_c is None else self.initial_c
        self._delay: DelayLine | None = None
        self._delay_dt = 0.0
        # the input that holds the initial temperature, so a plant that starts off-ambient is at rest
        self._u_rest = (self._temp - self.ambient_c) / self.true_gain

    def _delayed(self, u: float, dt: float) -> float:
        if self._delay is None or self._delay_dt != dt:
            self._delay = DelayLine(self.dead_time_s, dt, initial=self._u_rest)
            self._delay_dt = dt
        return self._delay.push(u)

    def set_dead_time(self, dead_time_s: float) -> None:
        """Model mismatch: the dead time changes in operation; the inputs already on their way stay."""
        if dead_time_s < 0.0:
            raise ValueError("dead time must be >= 0")
        self.dead_time_s = dead_time_s
        if self._delay is not None:
            self._delay = self._delay.resized(dead_time_s, self._delay_dt)

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        u = self.effective_inputs(u_pct, dist)[0] + self._u_rest
        ud = self._delayed(u, dt)
        target = self.ambient_c + dist.ambient_offset_c + self.true_gain * ud
        a = math.exp(-dt / self.true_time_constant)
        self._temp = a * self._temp + (1.0 - a) * target

    def temperatures(self) -> list[float]:
        return [self._temp]


@dataclass
class Sopdt(Plant):
    gain_c_per_pct: float
    time_constant_s: float
    time_constant2_s: float
    dead_time_s: float
    ambient_c: float = 25.0
    initial_c: float | None = None
    time_constant_scale: float = 1.0
    gain_scale: float = 1.0
    u_min_pct: float = 0.0
    u_max_pct: float = 100.0
    channels: int = field(default=1, init=False)

    def __post_init__(self) -> None:
        if min(self.time_constant_s, self.time_constant2_s) <= 0.0 or self.dead_time_s < 0.0:
            raise ValueError("time constants must be > 0 and dead time >= 0")
        if self.u_min_pct >= self.u_max_pct:
            raise ValueError(f"actuator range u_min_pct {self.u_min_pct} >= u_max_pct {self.u_max_pct}")
        self.reset()

    def reset(self) -> None:
        start = self.ambient_c if self.initial_c is None else self.initial_c
        self._t1 = start
        self._t2 = start
        self._u_rest = (start - self.ambient_c) / (self.gain_c_per_pct * self.gain_scale)
        self._delay: DelayLine | None = None
        self._delay_dt = 0.0

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        u = self.effective_inputs(u_pct, dist)[0] + self._u_rest
        if self._delay is None or self._delay_dt != dt:
            self._delay = DelayLine(self.dead_time_s, dt, initial=self._u_rest)
            self._delay_dt = dt
        ud = self._delay.push(u)
        target = self.ambient_c + dist.ambient_offset_c + self.gain_c_per_pct * self.gain_scale * ud
        t1 = self.time_constant_s * self.time_constant_scale
        t2 = self.time_constant2_s * self.time_constant_scale
        a1 = math.exp(-dt / t1)
        a2 = math.exp(-dt / t2)
        d1 = self._t1 - target
        # exact solution of the two lags in series for a constant input over the step
        if abs(t1 - t2) > 1e-9 * t1:
            coupling = t1 / (t1 - t2) * (a1 - a2)
        else:
            coupling = dt / t2 * a2
        self._t2 = target + (self._t2 - target) * a2 + d1 * coupling
        self._t1 = target + d1 * a1

    def temperatures(self) -> list[float]:
        return [self._t2]
