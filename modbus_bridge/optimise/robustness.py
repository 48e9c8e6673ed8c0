"""The true model of a scenario's zone 1 as the loop sees it, and the PID sets computed on it.

Loop model: the plant linearised at the operating point (exactly for the linear kinds, from a small
step of the plant model otherwise, plants/response.py) × the sensor lag 1/(lag·s + 1) × half a sample
of zero-order hold e^(−s·dt/2). Ms = max |1/(1 + C·G)| with FB_CtrlPid's form for C.
SIMC (Skogestad 2003, τc = θ, PI) and AMIGO (Åström & Hägglund 2004, PID) use a two-point FOPDT fit of
the true model's step response (control.md "Tuning formulas").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..plants.response import (
    FopdtFit,
    PlantModel,
    fit_fopdt,
    frequency_response,
    max_sensitivity,
    pid_frequency_response,
    step_response,
)
from ..scenario import Scenario
from .experiment import PidGains, last_tune_index

OMEGA_POINTS = 1500


def scored_step(sc: Scenario) -> tuple[int, float, float]:
    """(phase index, y0, r) of zone 1's scored window: from the first setpoint step between two phases
    that are not TUNE (a return from the tune setpoint is not the test), else from the first phase after
    tuning with a load or a ramp (the hand-over from TUNE is not the test either: a fixed set starts there
    at rest), else from the end of tuning; y0 = r = the setpoint in force without a step."""
    z = sc.zones[0]
    start = last_tune_index(z.phases)
    sp = z.phases[start].setpoint_c if start >= 0 else None
    for i in range(start + 1, len(z.phases)):
        p = z.phases[i]
        if p.setpoint_c is None:
            continue
        prev_is_tune = i > 0 and z.phases[i - 1].mode == "TUNE"
        if sp is not None and p.setpoint_c != sp and p.ramp_c_per_min is None and not prev_is_tune:
            return i, sp, p.setpoint_c
        sp = p.setpoint_c
    if sp is None:
        raise ValueError(f"{sc.name}: zone 1 has no setpoint")
    first_test = next((i for i in range(start + 1, len(z.phases))
                       if z.phases[i].disturbances or z.phases[i].ramp_c_per_min is not None), start + 1)
    return first_test, sp, sp


def operating_point(sc: Scenario) -> tuple[float, float]:
    """(y0, r) of the scored setpoint step (y0 = r without one)."""
    _, y0, r = scored_step(sc)
    return y0, r


def plant_model(sc: Scenario) -> PlantModel:
    return PlantModel(sc.plant_model, dict(sc.plant_params), sc.zones[0].channel)


@dataclass
class LoopModel:
    omegas: np.ndarray
    g: np.ndarray  # plant × sensor lag × half-sample hold
    fit: FopdtFit
    temp_c: float

    def ms(self, gains: PidGains) -> float:
        c = pid_frequency_response(gains.kp, gains.tn, gains.tv, gains.td_s, self.omegas)
        return max_sensitivity(c * self.g)


def loop_model(sc: Scenario) -> LoopModel:
    _, r = operating_point(sc)
    return loop_model_of(plant_model(sc), r, sc.dt_s, sc.zones[0].sensor.lag_s)


def loop_model_of(pm: PlantModel, temp_c: float, dt: float, sensor_lag_s: float = 0.0) -> LoopModel:
    """The loop model of a plant at temp_c, sampled every dt, with a sensor lag. Its FOPDT fit (for the
    rules) carries the loop's effective dead time: the plant's, plus the sensor lag and half a sample of
    hold (Skogestad's half rule), so a plant without dead time does not get an infinite gain."""
    t, s, _ = step_response(pm, temp_c, dt=min(dt, 0.1))
    plant_fit = fit_fopdt(t, s)
    fit = FopdtFit(plant_fit.gain, plant_fit.time_constant_s, plant_fit.dead_time_s + sensor_lag_s + dt / 2.0)
    slowest = fit.time_constant_s + fit.dead_time_s
    omegas = np.logspace(math.log10(0.01 / slowest), math.log10(math.pi / dt), OMEGA_POINTS)
    g = frequency_response(pm, temp_c, omegas)
    g = g / (sensor_lag_s * 1j * omegas + 1.0) * np.exp(-1j * omegas * dt / 2.0)
    return LoopModel(omegas, g, fit, temp_c)


def simc(fit: FopdtFit) -> PidGains:
    theta = max(fit.dead_time_s, 1e-3)
    tau_c = theta
    kc = fit.time_constant_s / (abs(fit.gain) * (tau_c + theta))
    return PidGains(kp=kc, tn=min(fit.time_constant_s, 4.0 * (tau_c + theta)), tv=0.0)


def amigo(fit: FopdtFit) -> PidGains:
    ell, tc = max(fit.dead_time_s, 1e-3), fit.time_constant_s
    kp = (0.2 + 0.45 * tc / ell) / abs(fit.gain)
    ti = ell * (0.4 * ell + 0.8 * tc) / (ell + 0.1 * tc)
    td = 0.5 * ell * tc / (0.3 * ell + tc)
    return PidGains(kp=kp, tn=ti, tv=td)
