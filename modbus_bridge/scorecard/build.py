"""The scorecard of one scenario: every controller on the same programme (zone 1 after the last TUNE
phase), against the bang-hold bound and the best fixed PID the optimiser finds.

Rows: the bound (true model, open loop), best fixed PID (optimise/search.py, IAE with the overshoot and
Ms limits), SIMC and AMIGO on the true model, and each variant of the scenario as written (the
project's self-tuned PID, fuzzy PID, ...). Columns: 2 % settling and overshoot of the first scored
setpoint step, IAE over the scored phases, 2 % recovery after the first load, Ms on the true model (a
fuzzy row: the worst Ms over the gain sets its adapter can reach, as the PLC reports it), and the ratios
of settling to the bound and of IAE to the best PID.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..optimise.executor import Executor
from ..optimise.experiment import (
    DERIVATIVE_FILTER_RATIO,
    Experiment,
    Outcome,
    PidGains,
    cost,
    judged,
    last_tune_index,
    run_experiment,
    tunes_cooling,
    variant_scenario,
)
from ..optimise.robustness import plant_model, scored_step
from ..optimise.search import Optimiser, Settings
from ..plants.response import BangBrakeHold, BangHold, bang_brake_hold_bound, bang_hold_bound
from ..scenario import Scenario, Variant

BOUND_HORIZON_FACTOR = 10.0
BOUND_ROW = "bound (bang-hold, true model)"
BRAKED_ROW = "bound with a brake (bang-brake-hold, true model)"


@dataclass
class Row:
    name: str
    settling_s: float = math.nan
    overshoot_pct: float = math.nan
    iae: float = math.nan
    recovery_s: float = math.nan
    ms: float = math.nan
    ms_what: str = ""  # which Ms when not the set's own (fuzzy rows: "worst reachable")
    gains: PidGains | None = None
    note: str = ""
    outcome: Outcome | None = None
    adapts: bool = False  # the gains move during the run (the fuzzy adapter on)
    cooling: bool = False  # `gains` is the cooling set (a zone tuned on its cooling side)
    vs_bound: float = math.nan
    vs_best: float = math.nan


@dataclass
class Card:
    scenario: Scenario
    rows: list[Row] = field(default_factory=list)
    bound: BangHold | None = None
    braked: BangBrakeHold | None = None  # the bound with a brake, where one settles sooner (linear plants)
    step: tuple[float, float] | None = None
    skipped: str | None = None
    tau: float = math.nan
    scored_phase: str | None = None  # zone 1's first scored phase: the setpoint step, or the first load


def applicable(sc: Scenario) -> str | None:
    """None, or why the scenario has nothing to score."""
    z = sc.zones[0]
    start = last_tune_index(z.phases) + 1
    scored = z.phases[start:]
    if not scored:
        return "no phase after tuning in zone 1"
    loads = {"load_step", "ambient_step", "fan", "filament"}
    has_load = any(d.kind in loads for p in scored for d in p.disturbances)
    has_sp = any(p.setpoint_c is not None for p in scored)
    if not (has_load or has_sp):
        return "no setpoint change or load after tuning in zone 1 (a fault scenario)"
    return None


def _step_figure(o: Outcome, key: str) -> float:
    """The first scored step's figure, as `judged` (NaN without one)."""
    for m in o.scored_metrics():
        if m.kind == "step" and (v := judged(m.values, key)) is not None:
            return float(v)
    return math.nan


def _tuned_gains(o: Outcome, cooling: bool = False) -> PidGains | None:
    """The set TUNE wrote: the heating set, or the cooling set of a zone tuned on its cooling side."""
    kp, tn, tv = (("tuned_kp_cool_pct_per_c", "tuned_tn_cool_s", "tuned_tv_cool_s") if cooling
                  else ("tuned_kp_pct_per_c", "tuned_tn_s", "tuned_tv_s"))
    for m in o.metrics:
        if m.kind == "tune" and kp in m.values:
            tv_s = float(m.values.get(tv, 0.0))
            return PidGains(float(m.values[kp]), float(m.values.get(tn, 0.0)), tv_s,
                            DERIVATIVE_FILTER_RATIO * tv_s)
    return None


def _row(name: str, o: Outcome, gains: PidGains | None, ms_of) -> Row:
    row = Row(name, outcome=o, gains=gains)
    # the step judged on the true temperature, as the bound is (`judged`)
    row.settling_s = _step_figure(o, "settling_time_2pct_s")
    if math.isnan(row.settling_s) and any(m.kind == "step" for m in o.scored_metrics()):
        row.settling_s = math.inf  # not inside the band by the end of the phase
    row.overshoot_pct = _step_figure(o, "overshoot_pct")
    row.iae = cost(o, "iae")
    for m in o.scored_metrics():
        if "recovery_time_2pct_s" in m.values:
            v = m.values["recovery_time_2pct_s"]
            row.recovery_s = float(v) if v is not None else math.nan
            break
    if gains is not None:
        row.ms = ms_of(gains)
    if o.error:
        row.note = o.error
    return row


def adapter_bound(o: Outcome) -> dict[str, float] | None:
    """The fuzzy adapter's Ms bound as the PLC reported it at the end of the run (the last scored phase the
    adapter ran in with a bound in use: analysis.ADAPTER_KEYS), None without one."""
    for m in reversed(o.scored_metrics()):
        if m.values.get("fuzzy_ms_reachable"):
            return {k: float(v) for k, v in m.values.items() if k.startswith("fuzzy_") and v is not None}
    return None


def variant_row(v: Variant, o: Outcome, ms_of: Callable[[PidGains], float], cooling: bool = False) -> Row:
    """A scenario variant's row. With the fuzzy adapter on, the gains move inside the box the adapter's Ms
    bound leaves: Ms is the worst over every set it can reach (fFuzzyMsReachable, on the identified model
    with the filter in use), not the base set's; without a bound in use, the base set's, said so."""
    row = _row(v.name, o, _tuned_gains(o, cooling), ms_of)
    row.adapts, row.cooling = bool(v.fuzzy), cooling
    bound = adapter_bound(o)
    if bound is not None:
        row.ms, row.ms_what = bound["fuzzy_ms_reachable"], "worst reachable"
        what = (
            f"Ms: worst over the gain sets the adapter can reach, on the identified model (bound "
            f"{_g(bound.get('fuzzy_ms_max'))}; ratio box {_pct(bound.get('fuzzy_box_share'))} kept, "
            f"base gains × {_g(bound.get('fuzzy_gain_scale'))})"
        )
    elif v.fuzzy:
        row.ms_what = "base set"
        what = "Ms of the base set (no Ms bound in use; the fuzzy gains move)"
    else:
        return row
    row.note = f"{row.note}; {what}" if row.note else what
    return row


def _g(v: float | None) -> str:
    return "–" if v is None else f"{v:.3g}"


def _pct(v: float | None) -> str:
    return "–" if v is None else f"{100.0 * v:.0f} %"


def build_card(sc: Scenario, executor: Executor, evals: int) -> Card:
    card = Card(sc)
    why = applicable(sc)
    if why:
        card.skipped = why
        return card
    opt = Optimiser(sc, Settings(cost="iae", evals=evals), executor)
    fit = opt.model.fit
    card.tau = fit.tau
    scored_from, y0, r = scored_step(sc)
    if y0 != r:
        card.step = (y0, r)
        horizon = BOUND_HORIZON_FACTOR * (fit.time_constant_s + fit.dead_time_s)
        card.bound = bang_hold_bound(plant_model(sc), y0, r, sc.dt_s, horizon)
        braked = bang_brake_hold_bound(plant_model(sc), y0, r, sc.dt_s, horizon)
        if braked is not None and braked.brake_s > 0.0 and braked.settling_s < card.bound.settling_s:
            card.braked = braked
    exps = [Experiment(v.name, variant_scenario(sc, i), None, scored_from) for i, v in enumerate(sc.variants)]
    outcomes = executor.map(run_experiment, exps)
    best = opt.run()  # evaluates SIMC and AMIGO first
    references = _reference_rows(card)
    rows = []
    best_row = None
    if best.best.outcome is not None:
        name = f"best fixed PID ({len(best.history)} experiments)"
        best_row = _row(name, best.best.outcome, best.best.gains, opt.model.ms)
        rows.append(best_row)
    for name, ev in opt.start_evaluations.items():
        if ev.outcome is not None:
            rows.append(_row(name, ev.outcome, ev.gains, opt.model.ms))
    cooling = tunes_cooling(sc.zones[0])
    for v, o in zip(sc.variants, outcomes, strict=True):
        rows.append(variant_row(v, o, opt.model.ms, cooling=cooling))
    best_iae = math.nan
    if best_row is not None:
        best_iae = best_row.iae
    elif card.bound is None and rows and rows[0].outcome is not None:
        best_iae = rows[0].iae
    for row in references + rows:
        if card.bound is not None and not math.isnan(row.settling_s) and math.isfinite(card.bound.settling_s):
            row.vs_bound = row.settling_s / card.bound.settling_s
        if row.outcome is not None and math.isfinite(best_iae) and best_iae > 0:
            row.vs_best = row.iae / best_iae
    limits = opt.settings
    for row in rows:
        if row.overshoot_pct > limits.max_overshoot_pct or row.ms > limits.max_ms:
            note = (
                f"outside the search limits (overshoot <= {limits.max_overshoot_pct:g} %, "
                f"Ms <= {limits.max_ms:g})"
            )
            row.note = f"{row.note}; {note}" if row.note else note
    rows = references + rows
    card.rows = rows
    card.scored_phase = sc.zones[0].phases[scored_from].name
    return card


def _reference_rows(card: Card) -> list[Row]:
    """The open-loop rows on the true model: the bound, and the bound with a brake where it settles sooner."""
    rows = []
    if card.bound is not None:
        b = card.bound
        note = f"{b.u_full:.0f} % for {b.switch_s:.1f} s, then {b.u_hold:.1f} %"
        rows.append(Row(BOUND_ROW, settling_s=b.settling_s, overshoot_pct=b.overshoot_pct, note=note))
    if card.braked is not None:
        k = card.braked
        note = (f"{k.u_full:.0f} % for {k.pulse_s:.1f} s, {k.u_brake:.0f} % for {k.brake_s:.1f} s, "
                f"then {k.u_hold:.1f} %")
        rows.append(Row(BRAKED_ROW, settling_s=k.settling_s, overshoot_pct=k.overshoot_pct, note=note))
    return rows


def window(o: Outcome, phase: str | None) -> tuple[np.ndarray, float]:
    """The samples from the start of `phase` (or of the scored window) to the end, and that start."""
    start = next((p[1] for p in o.phases if p[0] == phase), o.scored_start)
    return o.t >= start - 1e-9, start
