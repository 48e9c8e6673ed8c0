"""Offline analysis of a plant model (the "true model" of a scenario): rest input, step response around
an operating point, frequency response, a two-point FOPDT fit, the bang-hold bound and the bang-brake-hold
one (a brake between the two).

Everything here simulates the plant classes themselves, so it holds for every model the harness runs
(linear, nonlinear, multi-channel). Nonlinear plants are linearised by a small step around the
operating point; for the linear kinds `frequency_response` uses the transfer function exactly.
Multi-channel plants: the other channels hold the same input as the channel under study.
"""

from __future__ import annotations

import cmath
import copy
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import PLANT_MODELS
from .base import Plant, PlantDisturbance
from .linear import Fopdt, Sopdt
from .lti import _LtiPlant

SETTLE_CHUNK_S = 50.0
MAX_SETTLE_S = 50_000.0
SETTLED_REL = 1e-6
SMALL_STEP_PCT = 2.0
BAND_2PCT = 0.02
# two-point FOPDT fit (Smith): times at 28.3 % and 63.2 % of the final change
SMITH_LOW, SMITH_HIGH = 0.283, 0.632


@dataclass
class PlantModel:
    """A plant kind with its parameters, and the channel under study."""

    model: str
    params: dict
    channel: int = 0

    def build(self, **overrides) -> Plant:
        return PLANT_MODELS[self.model](**{**self.params, **overrides})


class _Sim:
    def __init__(self, pm: PlantModel, dt: float, start_c: float | None = None) -> None:
        self.pm, self.dt = pm, dt
        self.plant = pm.build()
        # the linear kinds are incremental: with initial_c they add the input that holds it to every
        # command, so their absolute input would be off; only the heat-balance plants start off-ambient
        if start_c is not None and not hasattr(self.plant, "_u_rest"):
            self.plant = pm.build(initial_c=start_c)
        self.dist = PlantDisturbance.for_channels(self.plant.channels)

    def run(self, u: Callable[[float], float], u_others: float, seconds: float, t0: float = 0.0):
        n = max(1, round(seconds / self.dt))
        out = np.empty(n)
        inputs = [u_others] * self.plant.channels
        c = self.pm.channel
        for k in range(n):
            inputs[c] = u(t0 + k * self.dt)
            self.plant.step(inputs, self.dt, self.dist)
            out[k] = self.plant.temperatures()[c]
        return out


def _settle(sim: _Sim, u: float, u_others: float | None = None) -> float:
    """Hold the channel at u and the others at u_others (default u) until the temperature stops moving;
    returns it. A chunk is longer than the dead time, so "not moving" is never the input still on its way
    through the delay."""
    others = u if u_others is None else u_others
    last = sim.plant.temperatures()[sim.pm.channel]
    chunk = max(SETTLE_CHUNK_S, 2.0 * float(getattr(sim.plant, "dead_time_s", 0.0) or 0.0))
    t = 0.0
    while t < MAX_SETTLE_S:
        y = sim.run(lambda _t: u, others, chunk)[-1]
        t += chunk
        if abs(y - last) <= SETTLED_REL * max(1.0, abs(y)):
            return float(y)
        last = y
    return float(last)


def steady_temperature(pm: PlantModel, u: float, dt: float = 0.5, u_others: float | None = None) -> float:
    return _settle(_Sim(pm, dt), u, u_others)


def rest_input(
    pm: PlantModel, temp_c: float, dt: float = 0.5, tol_c: float = 1e-4, u_others: float | None = None
) -> float:
    """The constant input (%) that holds the channel at temp_c (secant on the steady-state map), the other
    channels at u_others (default: the same input)."""
    plant = pm.build()
    lo, hi = plant.u_min_pct, plant.u_max_pct
    u0, u1 = 0.0 if lo <= 0.0 <= hi else lo, 0.5 * (lo + hi) if hi - lo > 1e-9 else hi
    if abs(u1 - u0) < 1e-6:
        u1 = hi
    y0, y1 = steady_temperature(pm, u0, dt, u_others), steady_temperature(pm, u1, dt, u_others)
    for _ in range(30):
        if abs(y1 - temp_c) < tol_c or y1 == y0:
            break
        u2 = u1 + (temp_c - y1) * (u1 - u0) / (y1 - y0)
        u2 = min(max(u2, lo), hi)
        u0, y0, u1 = u1, y1, u2
        y1 = steady_temperature(pm, u1, dt, u_others)
    if abs(y1 - temp_c) > max(0.05, 1e-3 * abs(temp_c)):
        raise ValueError(f"the plant cannot be held at {temp_c} °C with inputs {lo}..{hi} %")
    return u1


def step_response(
    pm: PlantModel, temp_c: float, du: float = SMALL_STEP_PCT, dt: float = 0.1, horizon_s: float | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """(t, dy, u0): response of the channel to a step of du % from rest at temp_c (held by u0)."""
    u0 = rest_input(pm, temp_c)
    plant = pm.build()
    if u0 + du > plant.u_max_pct:
        du = -du
    sim = _Sim(pm, dt, start_c=temp_c)
    base = _settle(sim, u0)
    if horizon_s is None:  # long enough to settle: keep going until the change stops
        chunks = [sim.run(lambda _t: u0 + du, u0, SETTLE_CHUNK_S)]
        while len(chunks) * SETTLE_CHUNK_S < MAX_SETTLE_S:
            nxt = sim.run(lambda _t: u0 + du, u0, SETTLE_CHUNK_S)
            chunks.append(nxt)
            if abs(nxt[-1] - nxt[0]) <= SETTLED_REL * max(1.0, abs(nxt[-1] - base)) * 10:
                break
        y = np.concatenate(chunks)
    else:
        y = sim.run(lambda _t: u0 + du, u0, horizon_s)
    t = dt * np.arange(1, y.size + 1)
    return np.concatenate([[0.0], t]), np.concatenate([[0.0], (y - base) / du]), u0


def frequency_response_from_step(t: np.ndarray, s: np.ndarray, omegas: np.ndarray) -> np.ndarray:
    """G(jw) = ∫ g(t) e^(−jwt) dt with g = ds/dt, s the unit step response sampled at t taken as piecewise
    linear (each segment integrated exactly), so nothing cancels at high frequency."""
    slopes = np.diff(s) / np.diff(t)
    w = np.asarray(omegas)[:, None]
    e = np.exp(-1j * w * t[None, :])
    segment = (e[:, :-1] - e[:, 1:]) / (1j * w)
    return segment @ slopes


def exact_frequency_response(plant: Plant, omegas: np.ndarray) -> np.ndarray | None:
    """The transfer function of the linear kinds, evaluated exactly (None for the others)."""
    s = 1j * omegas
    if isinstance(plant, Fopdt):
        g = plant.true_gain / (plant.true_time_constant * s + 1.0)
    elif isinstance(plant, Sopdt):
        sc = plant.time_constant_scale
        g = plant.gain_c_per_pct * plant.gain_scale
        g = g / ((plant.time_constant_s * sc * s + 1.0) * (plant.time_constant2_s * sc * s + 1.0))
    elif isinstance(plant, _LtiPlant):
        num, den = plant.transfer_function()
        ss = s * plant.time_constant_scale
        g = plant.gain_scale * np.polyval(num, ss) / np.polyval(den, ss)
    else:
        return None
    return g * np.exp(-s * plant.dead_time_s)


def frequency_response(pm: PlantModel, temp_c: float, omegas: np.ndarray, dt: float = 0.05) -> np.ndarray:
    exact = exact_frequency_response(pm.build(), omegas)
    if exact is not None:
        return exact
    t, s, _ = step_response(pm, temp_c, dt=dt)
    return frequency_response_from_step(t, s, omegas)


@dataclass
class FopdtFit:
    gain: float  # °C per %
    time_constant_s: float
    dead_time_s: float

    @property
    def tau(self) -> float:
        return self.dead_time_s / (self.dead_time_s + self.time_constant_s)


def fit_fopdt(t: np.ndarray, s: np.ndarray) -> FopdtFit:
    """Two-point (Smith) FOPDT fit of a unit step response: T = 1.5 (t63 − t28), L = t63 − T."""
    k = float(s[-1])
    frac = s / k

    def cross(level: float) -> float:
        i = int(np.argmax(frac >= level))
        if i == 0:
            return float(t[0])
        return float(t[i - 1] + (level - frac[i - 1]) * (t[i] - t[i - 1]) / (frac[i] - frac[i - 1]))

    t28, t63 = cross(SMITH_LOW), cross(SMITH_HIGH)
    tc = 1.5 * (t63 - t28)
    return FopdtFit(gain=k, time_constant_s=tc, dead_time_s=max(0.0, t63 - tc))


@dataclass
class BangHold:
    switch_s: float  # full power until this time after the step, then the holding power
    settling_s: float  # 2 % settling of the true temperature
    overshoot_pct: float
    u_full: float
    u_hold: float
    t: np.ndarray
    y: np.ndarray

    def inputs(self) -> np.ndarray:
        """The input at each of `t`."""
        return np.where(self.t < self.switch_s, self.u_full, self.u_hold)


def _settling(t: np.ndarray, y: np.ndarray, y0: float, r: float) -> float:
    band = BAND_2PCT * abs(r - y0)
    outside = np.flatnonzero(np.abs(y - r) > band)
    if outside.size == 0:
        return 0.0
    if outside[-1] == y.size - 1:
        return math.inf
    return float(t[outside[-1] + 1])


def _overshoot_pct(y: np.ndarray, y0: float, r: float) -> float:
    return max(0.0, float(np.max((y - r) * math.copysign(1.0, r - y0)))) / abs(r - y0) * 100.0


def _from_rest(pm: PlantModel, y0: float, r: float, dt: float) -> tuple[Plant, float, float, _Sim]:
    """The plant, the input that holds y0, the one that holds r beside the others at it, and a simulation
    at rest at y0 (to copy for each candidate input)."""
    u0 = rest_input(pm, y0)
    start = _Sim(pm, dt, start_c=y0)
    _settle(start, u0)
    return start.plant, u0, rest_input(pm, r, u_others=u0), start


def _first_step(t: float, dt: float, n: int) -> int:
    """The first of n steps of dt run with an input that changes at t."""
    return min(n, max(0, math.ceil(t / dt - 1e-9)))


def _plus_from(y: np.ndarray, k: int, change: np.ndarray) -> np.ndarray:
    """y with `change` (a response from the start) added from step k on: a later input step, superposed."""
    y[k:] += change[: y.size - k]
    return y


def _reach_s(t: np.ndarray, y_full: np.ndarray, y0: float, r: float, horizon_s: float) -> float:
    """When the response at full power towards r crosses r (horizon_s if never): no switch comes later."""
    reach = np.flatnonzero((y_full - r) * math.copysign(1.0, r - y0) >= 0.0)
    return float(t[reach[0]]) if reach.size else horizon_s


def _is_linear(plant: Plant) -> bool:
    """The kinds whose response to a sum of inputs is the sum of their responses (inputs within range)."""
    return isinstance(plant, (Fopdt, Sopdt, _LtiPlant))


def bang_hold_bound(pm: PlantModel, y0: float, r: float, dt: float, horizon_s: float) -> BangHold:
    """The fastest 2 % settling one switch within the actuator range gives from rest at y0 to r: full power
    (or full cooling), then the holding power, switched at the best time (grid of dt); the time-optimal input
    of a first-order lag, which a plant of higher order can beat with a brake between the two. The other
    channels of a multi-channel plant keep the input that held the start; the holding power is the one
    that holds r beside them.

    A linear plant is simulated twice, at full and at holding power: the switch at step k adds the holding
    response less the full-power one, both delayed by k (superposition, the same discrete model). Other
    plants are simulated once per candidate switch time."""
    plant, u0, ur, start = _from_rest(pm, y0, r, dt)
    u_full = plant.u_max_pct if r > y0 else plant.u_min_pct

    def simulated(ts: float) -> np.ndarray:
        return copy.deepcopy(start).run(lambda t: u_full if t < ts - 1e-9 else ur, u0, horizon_s)

    y_full = simulated(horizon_s)
    t_grid = dt * np.arange(1, y_full.size + 1)
    response = simulated
    if _is_linear(plant):
        change = simulated(0.0) - y_full  # the holding power from the start, less full power

        def response(ts: float) -> np.ndarray:
            return _plus_from(y_full.copy(), _first_step(ts, dt, y_full.size), change)

    def trial(ts: float) -> float:
        return _settling(t_grid, response(ts), y0, r)

    t_max = _reach_s(t_grid, y_full, y0, r, horizon_s)
    coarse = np.arange(0.0, t_max + dt, max(dt, t_max / 60.0))
    scores = [trial(ts) for ts in coarse]
    best = float(coarse[int(np.argmin(scores))])
    step = max(dt, t_max / 60.0)
    fine = np.arange(max(0.0, best - step), best + step + dt / 2, dt)
    settle, ts = min((trial(ts), ts) for ts in fine)
    y = response(ts)
    return BangHold(ts, settle, _overshoot_pct(y, y0, r), u_full, ur, t_grid, y)


@dataclass
class BangBrakeHold:
    """Full power towards r, then the other limit (the brake), then the holding power."""

    pulse_s: float  # the limit towards r until this time after the step
    brake_s: float  # then the other limit for this long (0: none, the bang-hold input)
    settling_s: float  # 2 % settling of the true temperature
    overshoot_pct: float
    u_full: float
    u_brake: float
    u_hold: float
    t: np.ndarray
    y: np.ndarray

    def inputs(self) -> np.ndarray:
        """The input at each of `t`."""
        braked = np.where(self.t < self.pulse_s + self.brake_s, self.u_brake, self.u_hold)
        return np.where(self.t < self.pulse_s, self.u_full, braked)


BRAKE_GRID = 100  # candidates per axis (pulse, brake) of the coarse grid; then every dt around the best
BRAKE_REFINE_CELLS = 2  # the fine grid spans this many coarse cells either side of the best


def bang_brake_hold_bound(
    pm: PlantModel, y0: float, r: float, dt: float, horizon_s: float
) -> BangBrakeHold | None:
    """The fastest 2 % settling two switches within the actuator range give from rest at y0 to r: full power
    (or full cooling), then the other limit, then the holding power; both times on a grid, refined to dt
    around its best (the settling time is not smooth in them: a local search stops in the wrong basin). A
    plant of order n > 1 needs up to n switches for the time-optimal input; the brake is the one a chain of
    lags gains most from, so this is nearer the physical limit than `bang_hold_bound` on such plants. The
    other channels of a multi-channel plant keep the input that held the start.

    Linear plants only (None otherwise): each candidate is a superposition of three simulated responses, as
    in `bang_hold_bound`; simulating every candidate of the grid would take minutes per plant."""
    if not _is_linear(pm.build()):
        return None
    plant, u0, ur, start = _from_rest(pm, y0, r, dt)
    towards, away = (plant.u_max_pct, plant.u_min_pct) if r > y0 else (plant.u_min_pct, plant.u_max_pct)

    def simulated(a: float, b: float) -> np.ndarray:
        def u(t: float) -> float:
            return towards if t < a - 1e-9 else (away if t < a + b - 1e-9 else ur)

        return copy.deepcopy(start).run(u, u0, horizon_s)

    y_full = simulated(horizon_s, 0.0)
    n = y_full.size
    t_grid = dt * np.arange(1, n + 1)
    to_away = simulated(0.0, horizon_s) - y_full  # the other limit from the start, less full power
    away_to_hold = simulated(0.0, 0.0) - y_full - to_away

    def response(a: float, b: float) -> np.ndarray:
        y = _plus_from(y_full.copy(), _first_step(a, dt, n), to_away)
        return _plus_from(y, _first_step(a + b, dt, n), away_to_hold)

    def best_of(pulses: np.ndarray, brakes: np.ndarray, best: tuple[float, float, float]):
        for a in pulses:
            for b in brakes:
                best = min(best, (_settling(t_grid, response(a, b), y0, r), a, b))
        return best

    def on_dt(lo: float, hi: float, step: float) -> np.ndarray:
        return dt * np.round(np.arange(max(0.0, lo), hi + step / 2, step) / dt)

    # full power alone reaching r bounds both times: a longer pulse or brake only moves further away
    span = _reach_s(t_grid, y_full, y0, r, horizon_s)
    step = max(dt, span / BRAKE_GRID)
    coarse = on_dt(0.0, span, step)
    best = best_of(coarse, coarse, (math.inf, 0.0, 0.0))
    around = BRAKE_REFINE_CELLS * step
    settle, a, b = best_of(on_dt(best[1] - around, best[1] + around, dt),
                           on_dt(best[2] - around, best[2] + around, dt), best)
    y = response(a, b)
    return BangBrakeHold(float(a), float(b), settle, _overshoot_pct(y, y0, r), towards, away, ur, t_grid, y)


def full_power_reach(pm: PlantModel, y0: float, r: float, dt: float, horizon_s: float,
                     u_others: float | None = None) -> float:
    """From rest at y0, the time the actuator's limit towards r takes to bring the channel into the 2 % band
    of r (inf when not within horizon_s): no controller limited to that range settles sooner. The other
    channels keep the input that held the start (all channels alike), or u_others when given."""
    u0 = rest_input(pm, y0, u_others=u_others)
    others = u0 if u_others is None else u_others
    plant = pm.build()
    u_full = plant.u_max_pct if r > y0 else plant.u_min_pct
    sim = _Sim(pm, dt, start_c=y0)
    _settle(sim, u0, others)
    y = sim.run(lambda _t: u_full, others, horizon_s)
    inside = np.flatnonzero(np.abs(y - r) <= BAND_2PCT * abs(r - y0))
    return float(dt * (inside[0] + 1)) if inside.size else math.inf


def pid_frequency_response(kp: float, tn: float, tv: float, td: float, omegas: np.ndarray) -> np.ndarray:
    """FB_CtrlPid's form: Kp (1 + 1/(Tn s) + Tv s/(Td s + 1)) (Tn <= 0: no I part)."""
    s = 1j * omegas
    c = np.ones_like(s)
    if tn > 0.0:
        c = c + 1.0 / (tn * s)
    if tv > 0.0:
        c = c + tv * s / (td * s + 1.0)
    return kp * c


def max_sensitivity(loop: np.ndarray) -> float:
    """Ms = max |1/(1 + L(jw))| over the grid; inf when the loop passes through -1."""
    den = np.abs(1.0 + loop)
    return float(np.max(1.0 / np.maximum(den, 1e-12)))


def sample_delay(omegas: np.ndarray, seconds: float) -> np.ndarray:
    return np.array([cmath.exp(-1j * w * seconds) for w in omegas])
