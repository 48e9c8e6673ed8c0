"""Linear plants given as a transfer function, so a user can bring their own model:

- `TransferFunctionPlant`: G(s) = num(s)/den(s) · e^(−Ls), coefficients in descending powers of s
  (seconds), gain in °C per % of heater power;
- `NLag`: K e^(−Ls)/(Ts + 1)^n, the n-lag (Strejc) model of a thermal chain of n equal capacities.

Both are converted to a state-space realisation and discretised exactly for a piecewise-constant input
(zero-order hold, `scipy.signal.cont2discrete`), once per step size and time-constant scale. Like the
FOPDT the model is incremental around the ambient temperature: T = Ta + G(s)·u, the ambient offset
enters where the FOPDT's does (through the lags, not through the dead time) and dead time is the
shared delay line on the heater input (base.py). `time_constant_scale` stretches the time axis of
G(s) (every pole and zero), `gain_scale` multiplies the gain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .base import DelayLine, Plant, PlantDisturbance

# leading numerator coefficients below this fraction of the largest one are treated as zeros
COEFF_EPS = 1e-12
MAX_ORDER = 20


def _poly(name: str, values: Sequence[float]) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty list of numbers")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must contain finite numbers only")
    nz = np.flatnonzero(np.abs(arr) > COEFF_EPS * max(1.0, float(np.max(np.abs(arr)))))
    if nz.size == 0:
        raise ValueError(f"{name} must not be all zeros")
    return arr[nz[0] :]


@dataclass
class _LtiPlant(Plant):
    """Exact ZOH simulation of a SISO transfer function with input dead time (see the module doc)."""

    ARRAY_FIELDS: ClassVar[tuple[str, ...]] = ()

    def transfer_function(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - interface
        raise NotImplementedError

    def _setup(self) -> None:
        if self.dead_time_s < 0.0:  # type: ignore[attr-defined]
            raise ValueError("dead time must be >= 0")
        if self.u_min_pct >= self.u_max_pct:
            raise ValueError(f"actuator range u_min_pct {self.u_min_pct} >= u_max_pct {self.u_max_pct}")
        num, den = self.transfer_function()
        if num.size > den.size:
            raise ValueError(
                f"improper transfer function: numerator degree {num.size - 1} > denominator degree "
                f"{den.size - 1}"
            )
        if den.size - 1 > MAX_ORDER:
            raise ValueError(f"order {den.size - 1} above {MAX_ORDER}")
        if den.size < 2:
            raise ValueError("the denominator must have degree >= 1 (a static gain is not a thermal plant)")
        if abs(den[-1]) <= COEFF_EPS * float(np.max(np.abs(den))):
            raise ValueError("the denominator has a root at s = 0: an integrating plant has no rest state")
        poles = np.roots(den)
        if np.any(poles.real >= 0.0):
            raise ValueError(f"unstable plant: pole(s) {', '.join(f'{p:.4g}' for p in poles if p.real >= 0)}")
        self.dc_gain = float(num[-1] / den[-1]) if num.size else 0.0
        if abs(self.dc_gain) <= 0.0:
            raise ValueError("the steady-state gain num(0)/den(0) must not be 0")
        from scipy import signal  # imported on first use: plants load with every command

        self._a, self._b, self._c, self._d = signal.tf2ss(num, den)
        self._disc: dict[tuple[float, float], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}
        self.reset()

    @property
    def true_gain(self) -> float:
        return self.dc_gain * self.gain_scale  # type: ignore[attr-defined]

    def reset(self) -> None:
        start = self.ambient_c if self.initial_c is None else self.initial_c  # type: ignore[attr-defined]
        self._u_rest = (start - self.ambient_c) / self.true_gain  # type: ignore[attr-defined]
        # the state at rest for the input u_rest: 0 = A x + B u
        self._x = -np.linalg.solve(self._a, self._b[:, 0] * self._u_rest * self.gain_scale)  # type: ignore[attr-defined]
        self._delay: DelayLine | None = None
        self._delay_dt = 0.0
        self._y = float(start)

    def _discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        scale = float(self.time_constant_scale)  # type: ignore[attr-defined]
        key = (dt, scale)
        if key not in self._disc:
            from scipy import signal

            # G(s·scale): the same model on a time axis stretched by `scale` = the nominal model over dt/scale
            ad, bd, cd, dd, _ = signal.cont2discrete((self._a, self._b, self._c, self._d), dt / scale, "zoh")
            self._disc[key] = (ad, bd[:, 0], cd[0], dd[0])
        return self._disc[key]

    def step(self, u_pct: Sequence[float], dt: float, dist: PlantDisturbance) -> None:
        u = self.effective_inputs(u_pct, dist)[0] + self._u_rest
        if self._delay is None or self._delay_dt != dt:
            self._delay = DelayLine(self.dead_time_s, dt, initial=self._u_rest)  # type: ignore[attr-defined]
            self._delay_dt = dt
        ud = self._delay.push(u)
        # the ambient offset acts like an input offset that gives that rise at steady state
        v = self.gain_scale * ud + dist.ambient_offset_c / self.dc_gain  # type: ignore[attr-defined]
        ad, bd, cd, dd = self._discrete(dt)
        self._x = ad @ self._x + bd * v
        self._y = self.ambient_c + float(cd @ self._x + dd[0] * v)  # type: ignore[attr-defined]

    def temperatures(self) -> list[float]:
        return [self._y]


@dataclass
class TransferFunctionPlant(_LtiPlant):
    """G(s) = num(s)/den(s) e^(−Ls): `num`, `den` in descending powers of s (°C per %, seconds)."""

    num: tuple[float, ...]
    den: tuple[float, ...]
    dead_time_s: float = 0.0
    ambient_c: float = 25.0
    initial_c: float | None = None
    time_constant_scale: float = 1.0
    gain_scale: float = 1.0
    u_min_pct: float = 0.0
    u_max_pct: float = 100.0
    channels: int = field(default=1, init=False)

    ARRAY_FIELDS: ClassVar[tuple[str, ...]] = ("num", "den")

    def __post_init__(self) -> None:
        self.num = tuple(float(v) for v in np.atleast_1d(self.num))
        self.den = tuple(float(v) for v in np.atleast_1d(self.den))
        self._setup()

    def transfer_function(self) -> tuple[np.ndarray, np.ndarray]:
        return _poly("num", self.num), _poly("den", self.den)


@dataclass
class NLag(_LtiPlant):
    """K e^(−Ls)/(Ts + 1)^n."""

    gain_c_per_pct: float
    time_constant_s: float
    order: float  # n >= 1, a whole number (TOML numbers arrive as float)
    dead_time_s: float = 0.0
    ambient_c: float = 25.0
    initial_c: float | None = None
    time_constant_scale: float = 1.0
    gain_scale: float = 1.0
    u_min_pct: float = 0.0
    u_max_pct: float = 100.0
    channels: int = field(default=1, init=False)

    def __post_init__(self) -> None:
        if self.time_constant_s <= 0.0:
            raise ValueError("time constant must be > 0")
        if self.gain_c_per_pct == 0.0:
            raise ValueError("gain must not be 0")
        if self.order != math.floor(self.order) or not 1 <= self.order <= MAX_ORDER:
            raise ValueError(f"order must be a whole number 1..{MAX_ORDER}, got {self.order}")
        self.order = int(self.order)
        self._setup()

    def transfer_function(self) -> tuple[np.ndarray, np.ndarray]:
        den = np.poly1d([1.0])
        for _ in range(self.order):
            den = den * np.poly1d([self.time_constant_s, 1.0])
        return np.array([self.gain_c_per_pct]), np.asarray(den.coeffs, dtype=float)
