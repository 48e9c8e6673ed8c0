"""Control performance metrics, as defined in reference/control.md ("Performance indices").

All functions take sampled traces (numpy arrays, time in s). Step metrics follow python-control's
`step_info` conventions so the two can be cross-checked: rise time from the first sample at 10 % to the
first sample at 90 % of the step; settling time = time of the first sample after the last one outside
the band (band = 2 % or 5 % of the step size); overshoot % = 100 (y_max - y_final)/(y_final - y_0).
Differences from step_info, on purpose: y_final is the setpoint (not the last sample), and every time
is measured from the step time t0 (not from the first sample).

Keys (units in the name): dead_time_s (first sample 2 % of the step away from y0), delay_time_s (50 %),
rise_time_s, settling_time_2pct_s, settling_time_5pct_s, overshoot_pct, undershoot_pct, peak_c,
iae_c_s, ise_c2_s, itae_c_s2, itse_c2_s2, ie_c_s, ss_peak_to_peak_c, ss_std_c (after the 2 % settling),
ss_output_std_pct, ss_true_ripple_c, ss_true_offset_c (output and true temperature after the settling),
true_overshoot_pct, true_settling_time_2pct_s (the step judged on the true temperature),
tv_output_pct (total variation sum |u_k - u_k-1|), pwm_switches_per_min, saturation_time_s,
max_deviation_c and recovery_time_2pct_s (load disturbances), tuning_duration_s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

RISE_LOW = 0.1
RISE_HIGH = 0.9
DEAD_TIME_FRACTION = 0.02
DELAY_TIME_FRACTION = 0.5
BAND_2PCT = 0.02
BAND_5PCT = 0.05


def _first_index(mask: np.ndarray) -> int | None:
    idx = np.flatnonzero(mask)
    return int(idx[0]) if idx.size else None


def _integral(t: np.ndarray, f: np.ndarray) -> float:
    if t.size < 2:
        return 0.0
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def settling_time(t: np.ndarray, y: np.ndarray, y_final: float, band: float, t0: float) -> float:
    """Time from t0 to the first sample after the last one outside |y - y_final| < band (NaN if never)."""
    outside = np.flatnonzero(np.abs(y - y_final) >= band)
    settled = 0 if outside.size == 0 else int(outside[-1]) + 1
    if settled >= t.size:
        return math.nan
    return float(t[settled] - t0)


@dataclass
class StepWindow:
    t: np.ndarray
    y: np.ndarray
    t0: float
    y0: float
    y_final: float

    @property
    def step(self) -> float:
        return self.y_final - self.y0


def overshoot_pct(y: np.ndarray, y0: float, y_final: float) -> float:
    """100 (y_max - y_final) / (y_final - y0), y_max taken in the step's direction; 0 when y stays short."""
    step = y_final - y0
    if step == 0.0 or y.size == 0:
        return math.nan
    size = abs(step)
    peak = float(np.max(math.copysign(1.0, step) * (y - y0)))
    return max(0.0, 100.0 * (peak - size) / size)


def step_metrics(w: StepWindow) -> dict[str, float]:
    """Step-response metrics of a window that starts at the step (t0, y0) and aims at y_final."""
    step = w.step
    if step == 0.0 or w.t.size == 0:
        return {}
    sign = math.copysign(1.0, step)
    dev = sign * (w.y - w.y0)  # progress towards the target, positive
    size = abs(step)
    out: dict[str, float] = {}

    def crossing(frac: float) -> float:
        i = _first_index(dev >= frac * size)
        return math.nan if i is None else float(w.t[i] - w.t0)

    i_dead = _first_index(dev > DEAD_TIME_FRACTION * size)
    out["dead_time_s"] = math.nan if i_dead is None else float(w.t[i_dead] - w.t0)
    out["delay_time_s"] = crossing(DELAY_TIME_FRACTION)
    lo, hi = crossing(RISE_LOW), crossing(RISE_HIGH)
    out["rise_time_s"] = hi - lo
    out["settling_time_2pct_s"] = settling_time(w.t, w.y, w.y_final, BAND_2PCT * size, w.t0)
    out["settling_time_5pct_s"] = settling_time(w.t, w.y, w.y_final, BAND_5PCT * size, w.t0)
    out["overshoot_pct"] = overshoot_pct(w.y, w.y0, w.y_final)
    out["undershoot_pct"] = max(0.0, -100.0 * float(dev.min()) / size)
    out["peak_c"] = float(w.y[int(np.argmax(dev))])
    out.update(error_integrals(w.t, w.y_final - w.y, w.t0))
    ts = out["settling_time_2pct_s"]
    out.update(steady_state_band(w.t, w.y, w.t0 + ts if not math.isnan(ts) else math.nan))
    return out


def error_integrals(t: np.ndarray, e: np.ndarray, t0: float) -> dict[str, float]:
    tau = t - t0
    return {
        "iae_c_s": _integral(t, np.abs(e)),
        "ise_c2_s": _integral(t, e * e),
        "itae_c_s2": _integral(t, tau * np.abs(e)),
        "itse_c2_s2": _integral(t, tau * e * e),
        "ie_c_s": _integral(t, e),
    }


def steady_state_band(t: np.ndarray, y: np.ndarray, t_settled: float) -> dict[str, float]:
    """Peak-to-peak and standard deviation of y from t_settled to the end of the window."""
    if math.isnan(t_settled):
        return {"ss_peak_to_peak_c": math.nan, "ss_std_c": math.nan}
    tail = y[t >= t_settled]
    if tail.size < 2:
        return {"ss_peak_to_peak_c": math.nan, "ss_std_c": math.nan}
    return {"ss_peak_to_peak_c": float(np.ptp(tail)), "ss_std_c": float(np.std(tail))}


def settled_noise_metrics(
    t: np.ndarray, output: np.ndarray, true_c: np.ndarray, setpoint: float, t_settled: float
) -> dict[str, float]:
    """What sensor noise does once the step has settled (2 %): standard deviation of the controller output
    (%), half the peak-to-peak of the true temperature (the ripple, degC) and its mean offset from the
    setpoint (degC). Empty when the step never settled or a trace is missing."""
    if math.isnan(t_settled) or output.size != t.size or true_c.size != t.size:
        return {}
    tail = t >= t_settled
    if np.count_nonzero(tail) < 2:
        return {}
    return {
        "ss_output_std_pct": float(np.std(output[tail])),
        "ss_true_ripple_c": float(np.ptp(true_c[tail])) / 2.0,
        "ss_true_offset_c": float(np.mean(true_c[tail]) - setpoint),
    }


def disturbance_metrics(
    t: np.ndarray, y: np.ndarray, setpoint: float, t_dist: float, band_c: float
) -> dict[str, float]:
    """Load-disturbance response: max deviation, and time from the disturbance until y is back inside
    setpoint +/- band_c for good (the band of the preceding setpoint step, 2 %)."""
    mask = t >= t_dist
    tt, yy = t[mask], y[mask]
    if tt.size == 0:
        return {}
    dev = yy - setpoint
    out = {"max_deviation_c": float(dev[int(np.argmax(np.abs(dev)))])}
    outside = np.flatnonzero(np.abs(dev) >= band_c)
    if outside.size == 0:
        out["recovery_time_2pct_s"] = 0.0
    elif int(outside[-1]) + 1 >= tt.size:
        out["recovery_time_2pct_s"] = math.nan
    else:
        out["recovery_time_2pct_s"] = float(tt[int(outside[-1]) + 1] - t_dist)
    out.update(error_integrals(tt, setpoint - yy, t_dist))
    return out


def effort_metrics(
    t: np.ndarray, u: np.ndarray, u_min: float, u_max: float, pwm: np.ndarray | None = None
) -> dict[str, float]:
    """Total variation of the output, time at saturation, PWM switches per minute."""
    out: dict[str, float] = {}
    if u.size:
        out["tv_output_pct"] = float(np.sum(np.abs(np.diff(u))))
        dt = np.diff(t, append=t[-1] + (t[-1] - t[-2] if t.size > 1 else 0.0))
        saturated = (u <= u_min + 1e-9) | (u >= u_max - 1e-9)
        out["saturation_time_s"] = float(np.sum(dt[saturated]))
    if pwm is not None and pwm.size > 1:
        switches = int(np.count_nonzero(np.diff(pwm.astype(np.int8))))
        minutes = (t[-1] - t[0]) / 60.0
        out["pwm_switches_per_min"] = switches / minutes if minutes > 0 else math.nan
    return out


def json_safe(metrics: dict[str, float]) -> dict[str, float | None]:
    """NaN/inf become null so metrics.json stays valid JSON."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in metrics.items()}
