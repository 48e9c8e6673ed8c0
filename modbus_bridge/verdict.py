"""The verdict of a run: every judged metric against the reference's figure (paper) and our goal.

Judged: the scenario's `[[target]]` entries (e.g. seed 003's overshoot, settling and load recovery of the
paper's fuzzy PID), and for every TUNE phase the identified plant against the plant's true parameters
(goal: within IDENTIFICATION_TOLERANCE, as the acceptance suite asks) when the plant has them.
A metric that is missing or not finite fails (an aborted run cannot pass).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .analysis import PhaseMetrics
from .loop import RunResult
from .scenario import Target

IDENTIFICATION_TOLERANCE = 0.10
IDENTIFIED = {  # metric -> the plant parameter it identifies
    "identified_ks_c_per_pct": "gain_c_per_pct",
    "identified_tu_s": "dead_time_s",
    "identified_tg_s": "time_constant_s",
}


@dataclass
class VerdictRow:
    variant: str
    zone: str
    phase: str
    metric: str
    measured: float | None
    paper: float | None
    goal: str  # e.g. "<= 5", "within 10 % of 10.6"
    vs_paper: str  # "better", "as good", "worse", "–"
    passed: bool

    @property
    def verdict(self) -> str:
        return "pass" if self.passed else "FAIL"


def _finite(v: object) -> float | None:
    return float(v) if isinstance(v, int | float) and math.isfinite(float(v)) else None


def _compare(measured: float | None, ref: float | None, better: str) -> str:
    if ref is None:
        return "–"
    if measured is None:
        return "worse"
    diff = measured - ref if better == "lower" else ref - measured
    return "better" if diff < 0 else "as good" if diff == 0 else "worse"


def _target_rows(target: Target, result: RunResult, pms: list[PhaseMetrics]) -> list[VerdictRow]:
    if target.variant is not None and target.variant != result.variant.name:
        return []
    rows = []
    zones = [pm.zone for pm in pms if pm.phase == target.phase] or [tr.name for tr in result.zones][:1]
    for zone in dict.fromkeys(zones):
        if target.zone is not None and zone != target.zone:
            continue
        pm = next((p for p in pms if p.zone == zone and p.phase == target.phase), None)
        measured = _finite(pm.values.get(target.metric)) if pm is not None else None
        op = "<=" if target.better == "lower" else ">="
        goal = "–" if target.goal is None else f"{op} {target.goal:g}"
        passed = measured is not None and (
            target.goal is None
            or (measured <= target.goal if target.better == "lower" else measured >= target.goal)
        )
        if target.goal is None:  # judged against the paper only
            passed = _compare(measured, target.paper, target.better) != "worse"
        rows.append(VerdictRow(result.variant.name, zone, target.phase, target.metric, measured, target.paper,
                               goal, _compare(measured, target.paper, target.better), passed))
    return rows


def _identification_rows(result: RunResult, pms: list[PhaseMetrics]) -> list[VerdictRow]:
    params = result.scenario.plant_params
    rows = []
    for pm in pms:
        if pm.kind != "tune":
            continue
        for metric, param in IDENTIFIED.items():
            true = _finite(params.get(param))
            if true is None or true <= 0 or metric not in pm.values:
                continue
            measured = _finite(pm.values.get(metric))
            ok = measured is not None and abs(measured - true) <= IDENTIFICATION_TOLERANCE * true
            goal = f"within {IDENTIFICATION_TOLERANCE:.0%} of {true:g}"
            row = VerdictRow(result.variant.name, pm.zone, pm.phase, metric, measured, None, goal, "–", ok)
            rows.append(row)
    return rows


def verdict_rows(runs: list[tuple[RunResult, list[PhaseMetrics]]]) -> list[VerdictRow]:
    rows: list[VerdictRow] = []
    for result, pms in runs:
        rows += _identification_rows(result, pms)
        for target in result.scenario.targets:
            rows += _target_rows(target, result, pms)
    return rows


def verdict_table(rows: list[VerdictRow]) -> tuple[list[str], list[list[str]]]:
    header = ["variant", "zone", "phase", "metric", "measured", "paper", "vs paper", "goal", "verdict"]
    body = [
        [
            r.variant,
            r.zone,
            r.phase,
            r.metric,
            "–" if r.measured is None else f"{r.measured:.4g}",
            "–" if r.paper is None else f"{r.paper:g}",
            r.vs_paper,
            r.goal,
            r.verdict,
        ]
        for r in rows
    ]
    return header, body
