"""Physically based (lumped heat-balance) plants, integrated with fixed-step RK4 (see base.py).

- NonlinearHotend (control.md T6): C dT/dt = P u - k (T - Ta)^E - h_fan f (T - Ta) - c_fil v (T - Ta),
  loss exponent E = 1.35 (RepRapFirmware's cooling-rate exponent), so the gain falls with temperature.
- MarlinHotend (control.md T3, Marlin MPC defaults): block + sensor node, dTs/dt = r (Tb - Ts).
- TclabTwin (control.md T4, tclab.TCLabModel equations): two heaters, two sensors, coupled.
- FormingPlatform (seed 000): liquid loop for the bioprinting forming platform held at a few °C, split
  output (compressor cooling u < 0, semiconductor heating u > 0), transport delay to the PT100.
- CureMould (seed 004): 2x2 mesh of heater nodes coupled to their neighbours, ambient lamp at 80 °C,
  exothermic epoxy cure heat (first-order Arrhenius kinetics) once the activation temperature is reached.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .base import DelayLine, Plant, PlantDisturbance, rk4_step

GAS_CONSTANT_J_MOL_K = 8.314
KELVIN_OFFSET = 273.15


class _DelayedInputs:
    """One dead-time delay line per channel, created for the step size in use."""

    def __init__(self, delay_s: float, channels: int) -> None:
        self.delay_s = delay_s
        self.channels = channels
        self._lines: list[DelayLine] = []
        self._dt = 0.0

    def push(self, values: Sequence[float], dt: float) -> list[float]:
        if not self._lines or self._dt != dt:
            self._lines = [DelayLine(self.delay_s, dt) for _ in range(self.channels)]
            self._dt = dt
        return [line.push(v) for line, v in zip(self._lines, values, strict=True)]


@dataclass
class LumpedPlant(Plant):
    """Scaffolding of the RK4 heat-balance plants: start state, input dead time, ambient, integration.
    A subclass sets `channels`, STATE_NODES (states that start at the initial temperature), EXTRA_STATES
    (states that start at 0) and `delay_s()`, and writes only its heat balance in `step()`."""

    ambient_c: float = 25.0
    initial_c: float | None = None
    time_constant_scale: float = 1.0
    max_substep_s: float = 0.5

    STATE_NODES: ClassVar[int] = 1
    EXTRA_STATES: ClassVar[int] = 0

    def __post_init__(self) -> None:
        self.reset()

    def delay_s(self) -> float:
        return self.dead_time_s  # type: ignore[attr-defined]

    def reset(self) -> None:
        start = self.ambient_c if self.initial_c is None else self.initial_c
        self._x = np.concatenate([np.full(self.STATE_NODES, float(start)), np.zeros(self.EXTRA_STATES)])
        self._delay = _DelayedInputs(self.delay_s(), self.channels)

    def delayed_inputs(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> list[float]:
        return self._delay.push(self.effective_inputs(u_pct, dist), dt)

    def ambient(self, dist: PlantDisturbance) -> float:
        return self.ambient_c + dist.ambient_offset_c

    def integrate(self, f, dt: float) -> None:
        self._x = rk4_step(f, self._x, dt, self.max_substep_s)


@dataclass
class NonlinearHotend(LumpedPlant):
    heater_w: float = 40.0
    heat_capacity_j_k: float = 16.7
    loss_coeff_w: float = 0.0  # k in k (dT)^E; 0 -> derived from max_rise_c
    loss_exponent: float = 1.35
    max_rise_c: float = 340.0  # steady-state rise at 100 % (control.md T1: K = 340 °C)
    fan_w_k: float = 0.029  # extra loss at full fan (Marlin MPC: 0.097 - 0.068 W/K)
    filament_j_k_mm: float = 0.0056
    dead_time_s: float = 5.5
    channels: int = field(default=1, init=False)

    def __post_init__(self) -> None:
        if self.loss_coeff_w <= 0.0:
            self.loss_coeff_w = self.heater_w / self.max_rise_c**self.loss_exponent
        self.reset()

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        (u,) = self.delayed_inputs(u_pct, dt, dist)
        zd = dist.zones[0]
        ta = self.ambient(dist)
        cap = self.heat_capacity_j_k * self.time_constant_scale
        power = self.heater_w * u / 100.0

        def f(x: np.ndarray) -> np.ndarray:
            dtemp = x[0] - ta
            loss = self.loss_coeff_w * math.copysign(abs(dtemp) ** self.loss_exponent, dtemp)
            loss += (self.fan_w_k * zd.fan + self.filament_j_k_mm * zd.filament_mm_s) * dtemp
            return np.array([(power - loss) / cap])

        self.integrate(f, dt)

    def temperatures(self) -> list[float]:
        return [float(self._x[0])]


@dataclass
class MarlinHotend(LumpedPlant):
    heater_w: float = 40.0
    block_heat_capacity_j_k: float = 16.7
    ambient_xfer_w_k: float = 0.068
    fan_extra_xfer_w_k: float = 0.029
    sensor_response_per_s: float = 0.22
    filament_j_k_mm: float = 0.0056
    dead_time_s: float = 0.0
    channels: int = field(default=1, init=False)

    STATE_NODES: ClassVar[int] = 2  # block, sensor

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        (u,) = self.delayed_inputs(u_pct, dt, dist)
        zd = dist.zones[0]
        ta = self.ambient(dist)
        cap = self.block_heat_capacity_j_k * self.time_constant_scale
        power = self.heater_w * u / 100.0
        xfer = self.ambient_xfer_w_k + self.fan_extra_xfer_w_k * zd.fan
        xfer += self.filament_j_k_mm * zd.filament_mm_s
        r = self.sensor_response_per_s

        def f(x: np.ndarray) -> np.ndarray:
            return np.array([(power - xfer * (x[0] - ta)) / cap, r * (x[0] - x[1])])

        self.integrate(f, dt)

    def temperatures(self) -> list[float]:
        return [float(self._x[1])]


@dataclass
class TclabTwin(LumpedPlant):
    """dH_i/dt = P Q_i/5720 + (Ta - H_i)/20 -/+ (H1 - H2)/100; dT_i/dt = (H_i - T_i)/140."""

    heater_factor: float = 200.0
    heater_divisor: float = 5720.0
    ambient_time_s: float = 20.0
    coupling_time_s: float = 100.0
    sensor_time_s: float = 140.0
    ambient_c: float = 21.0
    dead_time_s: float = 0.0
    channels: int = field(default=2, init=False)

    STATE_NODES: ClassVar[int] = 4  # H1, H2, T1, T2

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        q = self.delayed_inputs(u_pct, dt, dist)
        ta = self.ambient(dist)
        s = self.time_constant_scale

        heat = [self.heater_factor * qi / self.heater_divisor for qi in q]

        def f(x: np.ndarray) -> np.ndarray:
            h1, h2, t1, t2 = x
            cross = (h1 - h2) / self.coupling_time_s
            return np.array(
                [
                    (heat[0] + (ta - h1) / self.ambient_time_s - cross) / s,
                    (heat[1] + (ta - h2) / self.ambient_time_s + cross) / s,
                    (h1 - t1) / self.sensor_time_s,
                    (h2 - t2) / self.sensor_time_s,
                ]
            )

        self.integrate(f, dt)

    def temperatures(self) -> list[float]:
        return [float(self._x[2]), float(self._x[3])]


@dataclass
class FormingPlatform(LumpedPlant):
    """Seed 000: liquid bath (heater + compressor) pumped through the platform; PT100 at the loop exit."""

    heater_w: float = 60.0
    cooler_w: float = 60.0
    bath_heat_capacity_j_k: float = 2000.0
    bath_ambient_w_k: float = 1.0
    bath_platform_w_k: float = 5.0
    platform_heat_capacity_j_k: float = 300.0
    platform_ambient_w_k: float = 0.3
    transport_delay_s: float = 8.0
    ambient_c: float = 20.0
    u_min_pct: float = -100.0
    u_max_pct: float = 100.0
    channels: int = field(default=1, init=False)

    STATE_NODES: ClassVar[int] = 2  # bath, platform

    def delay_s(self) -> float:
        return self.transport_delay_s

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        (u,) = self.delayed_inputs(u_pct, dt, dist)
        power = self.heater_w * u / 100.0 if u >= 0.0 else self.cooler_w * u / 100.0
        ta = self.ambient(dist)
        s = self.time_constant_scale

        def f(x: np.ndarray) -> np.ndarray:
            bath, plat = x
            q_bp = self.bath_platform_w_k * (bath - plat)
            return np.array(
                [
                    (power - self.bath_ambient_w_k * (bath - ta) - q_bp) / (self.bath_heat_capacity_j_k * s),
                    (q_bp - self.platform_ambient_w_k * (plat - ta)) / (self.platform_heat_capacity_j_k * s),
                ]
            )

        self.integrate(f, dt)

    def temperatures(self) -> list[float]:
        return [float(self._x[1])]


@dataclass
class CureMould(LumpedPlant):
    """Seed 004: 2x2 heater nodes; node i: C dT_i/dt = P u_i - h (T_i - Ta) - g sum_nb (T_i - T_j) + q_cure_i,
    q_cure = H dalpha/dt, dalpha/dt = k_ref exp(-Ea/R (1/T - 1/T_ref)) (1 - alpha) when T >= T_act."""

    heater_w: float = 50.0
    node_heat_capacity_j_k: float = 400.0
    ambient_xfer_w_k: float = 0.2
    neighbour_xfer_w_k: float = 0.3
    cure_enthalpy_j: float = 20_000.0
    activation_c: float = 120.0
    cure_rate_ref_per_s: float = 1.0 / 900.0
    cure_ref_c: float = 180.0
    cure_activation_energy_j_mol: float = 60_000.0
    dead_time_s: float = 2.0
    ambient_c: float = 80.0
    max_substep_s: float = 1.0
    channels: int = field(default=4, init=False)

    # 2x2 mesh, nodes numbered row-major: 0 1 / 2 3; each node touches two neighbours
    NEIGHBOURS = ((1, 2), (0, 3), (0, 3), (1, 2))

    STATE_NODES: ClassVar[int] = 4  # node temperatures
    EXTRA_STATES: ClassVar[int] = 4  # degree of cure per node

    def cure_rate(self, temp_c: float, alpha: float) -> float:
        if temp_c < self.activation_c or alpha >= 1.0:
            return 0.0
        inv = 1.0 / (temp_c + KELVIN_OFFSET) - 1.0 / (self.cure_ref_c + KELVIN_OFFSET)
        arrhenius = math.exp(-self.cure_activation_energy_j_mol / GAS_CONSTANT_J_MOL_K * inv)
        return self.cure_rate_ref_per_s * arrhenius * (1.0 - alpha)

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        u = self.delayed_inputs(u_pct, dt, dist)
        ta = self.ambient(dist)
        cap = self.node_heat_capacity_j_k * self.time_constant_scale

        def f(x: np.ndarray) -> np.ndarray:
            d = np.zeros(8)
            for i in range(4):
                ti = x[i]
                rate = self.cure_rate(ti, x[4 + i])
                q = self.heater_w * u[i] / 100.0 - self.ambient_xfer_w_k * (ti - ta)
                q -= sum(self.neighbour_xfer_w_k * (ti - x[j]) for j in self.NEIGHBOURS[i])
                q += self.cure_enthalpy_j * rate
                d[i] = q / cap
                d[4 + i] = rate
            return d

        self.integrate(f, dt)

    def temperatures(self) -> list[float]:
        return [float(v) for v in self._x[:4]]

    def degree_of_cure(self) -> list[float]:
        return [float(v) for v in self._x[4:]]
