"""The controller values a run keeps per phase beside its trace, one entry each: the binding role it is
read through (`binding.py` holds the register names), its metric key in metrics.json, and its column in
the report's table of its group. A new value is added here and in the binding, nowhere else in the
harness: the loop closer reads what the groups list, the analysis names it, the reports show it.

- TUNED: what TUNE identified and tuned, kept from the end of a TUNE phase. The gains and the identified
  plant are also traced through the run (the plot's gain panels); the rest is read with them.
- ADAPTER: the fuzzy adapter's Ms bound, kept while its coil is on.
- HEATUP: the plant as the model-based setpoint response's limit phase saw it, kept while a response runs.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class KeptValue:
    role: str  # binding role
    metric: str  # key in the phase's metrics (unit in the name)
    label: str = ""  # column in the report's table of its group ("": not a column)
    traced: bool = False  # also read into the trace's gain columns through the run


TUNED: tuple[KeptValue, ...] = (
    KeptValue("ks", "identified_ks_c_per_pct", "Ks (°C/%)", traced=True),
    KeptValue("tu", "identified_tu_s", "Tu (s)", traced=True),
    KeptValue("tg", "identified_tg_s", "Tg (s)", traced=True),
    KeptValue("kp", "tuned_kp_pct_per_c", "Kp (%/°C)", traced=True),
    KeptValue("tn", "tuned_tn_s", "Tn (s)", traced=True),
    KeptValue("tv", "tuned_tv_s", "Tv (s)", traced=True),
    KeptValue("kp_cool", "tuned_kp_cool_pct_per_c", traced=True),
    KeptValue("tn_cool", "tuned_tn_cool_s", traced=True),
    KeptValue("tv_cool", "tuned_tv_cool_s", traced=True),
    KeptValue("noise_pp", "identified_noise_pp_c", "noise p-p (°C)"),  # sensor noise TUNE measured at rest
    KeptValue("noise_interval", "identified_noise_interval_s", "noise held (s)"),  # the PV's update interval
    KeptValue("t_filter", "tuned_filter_s", "filter (s)"),  # the actual-value filter sized from it
    KeptValue("ms", "tuned_ms", "Ms"),  # of the tuned set on the identified model
    KeptValue("order", "identified_order", "model order"),  # 1 FOPDT, n >= 2 the n-lag fitted
    KeptValue("fit_rms", "identified_fit_rms_pct", "fit rms (% of rise)"),  # that model's residual
)

# the coil that is on while the adapter runs; its values are kept only while a bound is in use
# (fz_ms_reachable 0: none)
ADAPTER_GATE = "fuzzy"
ADAPTER: tuple[KeptValue, ...] = (
    KeptValue("fz_ms_reachable", "fuzzy_ms_reachable", "Ms worst reachable"),
    KeptValue("fz_ms_max", "fuzzy_ms_max", "Ms bound"),
    KeptValue("fz_gain_scale", "fuzzy_gain_scale", "base gains ×"),
    KeptValue("fz_box_share", "fuzzy_box_share", "ratio box kept"),
)

# the response's state, non-zero while one runs
HEATUP_GATE = "heatup_state"
HEATUP: tuple[KeptValue, ...] = (
    KeptValue("heatup_tu", "heatup_tu_seen_s"),
    KeptValue("heatup_tg", "heatup_tg_seen_s"),
)


def roles(values: tuple[KeptValue, ...], traced: bool | None = None) -> tuple[str, ...]:
    """binding roles of the values (traced True/False: only those that are / are not traced)"""
    return tuple(v.role for v in values if traced is None or v.traced == traced)


def metric_of(values: tuple[KeptValue, ...]) -> dict[str, str]:
    """binding role -> metric key"""
    return {v.role: v.metric for v in values}


def columns(values: tuple[KeptValue, ...]) -> tuple[tuple[str, str], ...]:
    """(metric key, column label) of the values shown as columns, in order"""
    return tuple((v.metric, v.label) for v in values if v.label)
