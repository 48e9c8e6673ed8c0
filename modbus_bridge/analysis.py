"""Metrics of a finished run: one record per zone and phase (metric names as in metrics.py / control.md).

Per phase:
- a setpoint step at the phase start (not a ramp): step metrics from the phase start, y0 = process value
  at the start, y_final = the new setpoint;
- a TUNE phase: tuning_duration_s (until the controller reports TUNED), the identified plant
  (ks, tu, tg), the sensor noise measured at rest, the tuned gains, the actual-value filter sized from
  that noise, the set's Ms, and the PV excursion during tuning;
- a load/ambient/fan/filament disturbance: max deviation and recovery into the 2 % band of the last
  setpoint step (so "back inside the 2 % band" means the same band as the step's settling);
- a ramp: tracking error (IAE, max |e|) over the phase;
- a phase the fuzzy adapter ran in, with its Ms bound in use: the worst Ms over the gain sets it can reach,
  the bound, the scale of the base gains and the share of the ratio box kept (as at the phase end);
- a phase a model-based setpoint response ran in: the plant's dead time and time constant as its limit
  phase saw them (heatup_tu_seen_s, heatup_tg_seen_s);
- always: output total variation, saturation time, PWM switches per minute (PWM runs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import kept_values
from .loop import PhaseRecord, RunResult, ZoneTrace
from .metrics import (
    BAND_2PCT,
    StepWindow,
    disturbance_metrics,
    effort_metrics,
    error_integrals,
    overshoot_pct,
    settled_noise_metrics,
    settling_time,
    step_metrics,
)

LOAD_KINDS = ("load_step", "ambient_step", "fan", "filament")
TUNE_KEYS = kept_values.metric_of(kept_values.TUNED)
# the fuzzy adapter's Ms bound at the end of a phase it ran in (fz_ms_reachable 0: no bound in use, left out)
ADAPTER_KEYS = kept_values.metric_of(kept_values.ADAPTER)
# the plant as a model-based setpoint response that ran in the phase measured it (its limit phase)
HEATUP_KEYS = kept_values.metric_of(kept_values.HEATUP)


@dataclass
class PhaseMetrics:
    zone: str
    phase: str
    kind: str  # step, tune, disturbance, ramp, hold
    t_start_s: float
    t_end_s: float
    outcome: str
    values: dict[str, float] = field(default_factory=dict)
    info: dict[str, object] = field(default_factory=dict)


def _window(tr: ZoneTrace, rec: PhaseRecord) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    t = np.asarray(tr.t)
    mask = (t >= rec.t_start - 1e-9) & (t < rec.t_end - 1e-9)
    return t[mask], np.asarray(tr.pv)[mask], np.asarray(tr.u)[mask], np.asarray(tr.setpoint)[mask]


HOLD_SETTLED_SHARE = 0.5


def _in_window(values: list[float], tr: ZoneTrace, rec: PhaseRecord) -> np.ndarray:
    """A trace column over the phase window of `_window` (empty when the trace was not recorded)."""
    if len(values) != len(tr.t):
        return np.asarray([])
    t = np.asarray(tr.t)
    return np.asarray(values)[(t >= rec.t_start - 1e-9) & (t < rec.t_end - 1e-9)]


def zone_metrics(result: RunResult, tr: ZoneTrace) -> list[PhaseMetrics]:
    out: list[PhaseMetrics] = []
    last_step = math.nan
    plant = result.scenario.build_plant()
    for rec in tr.phases:
        t, y, u, sp = _window(tr, rec)
        pm = PhaseMetrics(
            zone=tr.name,
            phase=rec.name,
            kind="hold",
            t_start_s=rec.t_start,
            t_end_s=rec.t_end,
            outcome=rec.outcome,
            info={"mode": rec.mode, "fuzzy": rec.fuzzy, "setpoint_c": rec.setpoint},
        )
        if t.size == 0:
            out.append(pm)
            continue
        is_step = (
            rec.ramp_c_per_min is None
            and not math.isnan(rec.setpoint)
            and (math.isnan(rec.setpoint_before) or rec.setpoint != rec.setpoint_before)
        )
        if rec.mode == "TUNE":
            pm.kind = "tune"
            if rec.outcome == "ok":
                pm.values["tuning_duration_s"] = rec.t_end - rec.t_start
            pm.values["tuning_pv_excursion_c"] = float(np.max(y) - np.min(y))
            for key, val in rec.tuned.items():
                pm.values[TUNE_KEYS[key]] = val
            if is_step:
                last_step = abs(rec.setpoint - rec.pv_start)
        elif is_step and abs(rec.setpoint - rec.pv_start) > 0.0:
            pm.kind = "step"
            w = StepWindow(t=t, y=y, t0=rec.t_start, y0=rec.pv_start, y_final=rec.setpoint)
            pm.values.update(step_metrics(w))
            last_step = abs(w.step)
            settled = rec.t_start + pm.values["settling_time_2pct_s"]
            output, true_c = _in_window(tr.y, tr, rec), _in_window(tr.true_c, tr, rec)
            pm.values.update(settled_noise_metrics(t, output, true_c, rec.setpoint, settled))
            if true_c.size:
                # the process's own overshoot and settling: a quantised, noisy PV adds its noise counts to the
                # peak, and noise wider than the band keeps a PV outside a band its process is inside
                pm.values["true_overshoot_pct"] = overshoot_pct(true_c, float(true_c[0]), rec.setpoint)
                pm.values["true_settling_time_2pct_s"] = settling_time(
                    t, true_c, rec.setpoint, BAND_2PCT * abs(w.step), rec.t_start
                )
        elif rec.ramp_c_per_min is not None:
            pm.kind = "ramp"
            e = sp - y
            pm.values.update(error_integrals(t, e, rec.t_start))
            pm.values["max_tracking_error_c"] = float(np.max(np.abs(e)))
        if pm.kind == "hold" and not rec.disturbances and rec.mode != "MANUAL":
            # a hold without a step: what the noise does over its second half (the first may still settle)
            output, true_c = _in_window(tr.y, tr, rec), _in_window(tr.true_c, tr, rec)
            half = rec.t_start + HOLD_SETTLED_SHARE * (rec.t_end - rec.t_start)
            pm.values.update(settled_noise_metrics(t, output, true_c, float(sp[-1]), half))
        loads = [d for d in rec.disturbances if d[1] in LOAD_KINDS]
        if loads:
            pm.kind = "disturbance" if pm.kind == "hold" else pm.kind
            t_dist = loads[0][0]
            band = BAND_2PCT * last_step if not math.isnan(last_step) else math.nan
            pm.values.update(disturbance_metrics(t, y, float(sp[-1]), t_dist, band))
            pm.info["band_c"] = band
            pm.info["disturbances"] = [{"t_s": d[0], "kind": d[1], "value": d[2]} for d in rec.disturbances]
        elif rec.disturbances:
            pm.info["disturbances"] = [{"t_s": d[0], "kind": d[1], "value": d[2]} for d in rec.disturbances]
        pwm = (
            np.asarray(tr.pwm)[(np.asarray(tr.t) >= rec.t_start) & (np.asarray(tr.t) < rec.t_end)]
            if tr.pwm
            else None
        )
        # effort on the controller's analog output (with PWM the applied duty is 0/100 % most of the time)
        y_cmd = (
            np.asarray(tr.y)[(np.asarray(tr.t) >= rec.t_start) & (np.asarray(tr.t) < rec.t_end)]
            if len(tr.y) == len(tr.t)
            else u
        )
        pm.values.update(effort_metrics(t, y_cmd, plant.u_min_pct, plant.u_max_pct, pwm))
        adapter = rec.running.get("adapter", {})
        if adapter.get("fz_ms_reachable", 0.0) > 0.0:
            pm.values.update({ADAPTER_KEYS[k]: v for k, v in adapter.items()})
        pm.values.update({HEATUP_KEYS[k]: v for k, v in rec.running.get("heatup", {}).items()})
        out.append(pm)
    return out


def run_metrics(result: RunResult) -> list[PhaseMetrics]:
    return [pm for tr in result.zones for pm in zone_metrics(result, tr)]
