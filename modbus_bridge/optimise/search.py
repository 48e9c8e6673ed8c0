"""Nelder-Mead (scipy.optimize) on Kp, Tn, Tv in log coordinates, every cost value a closed-loop
experiment over Modbus (experiment.py) run through the executor (executor.py).

J = cost · (1 + W·(max(0, OS − OS_max)/max(OS_max, 0.5) + max(0, Ms − Ms_max)/Ms_max)), W = 10: the
overshoot is measured in the experiment, Ms on the true model (robustness.py). Start: the better
of AMIGO and SIMC on the FOPDT fit of the true model; initial simplex: seed 004's regular simplex
(edge = a factor 2 in each parameter), evaluated in parallel. `seed` is the sensor-noise seed of every
experiment (the same noise for every candidate), so a run is reproducible bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..scenario import Scenario
from .executor import Executor
from .experiment import (
    Experiment,
    Outcome,
    PidGains,
    cost,
    fixed_gain_scenario,
    max_overshoot,
    run_experiment,
)
from .robustness import LoopModel, amigo, loop_model, scored_step, simc

PENALTY_WEIGHT = 10.0
SIMPLEX_EDGE = math.log(2.0)
FAILED_COST = 1e12
SETTLE_TIME_CONSTANTS = 4.0
MIN_TV_S = 1e-3  # log coordinates: a PI set starts at Tv = 1 ms (no D in effect)


@dataclass
class Settings:
    cost: str = "iae"
    max_overshoot_pct: float = 2.0
    max_ms: float = 2.0
    seed: int | None = None
    evals: int = 40
    plc: str | None = None
    settle_s: float | None = None  # hold replacing TUNE; None: 4 (T + L) of the true model's fit


@dataclass
class Evaluation:
    gains: PidGains
    cost: float
    objective: float
    overshoot_pct: float
    ms: float
    error: str | None = None
    outcome: Outcome | None = field(default=None, repr=False)


@dataclass
class Result:
    best: Evaluation
    start: Evaluation
    history: list[Evaluation] = field(default_factory=list)
    settle_s: float = 0.0
    outcome: Outcome | None = None


def seed004_simplex(x0: np.ndarray, edge: float) -> np.ndarray:
    """Seed 004's starting simplex: x_ij = x_1j + X_ij·δ with p and q on the rows (regular simplex)."""
    k = x0.size
    p = (math.sqrt(k + 1) + k - 1) / (k * math.sqrt(2.0))
    q = (math.sqrt(k + 1) - 1) / (k * math.sqrt(2.0))
    rows = [np.zeros(k)] + [np.where(np.arange(k) == i, p, q) for i in range(k)]
    return x0[None, :] + edge * np.array(rows)


def gains_of(x: np.ndarray) -> PidGains:
    kp, tn, tv = np.exp(x)
    return PidGains(kp=float(kp), tn=float(tn), tv=float(tv))


class Optimiser:
    def __init__(self, scenario: Scenario, settings: Settings, executor: Executor) -> None:
        if settings.evals < 1:
            raise ValueError(f"--evals must be >= 1, got {settings.evals}")
        self.sc, self.settings, self.executor = scenario, settings, executor
        self.model: LoopModel = loop_model(scenario)
        fit = self.model.fit
        self.settle_s = settings.settle_s or SETTLE_TIME_CONSTANTS * (fit.time_constant_s + fit.dead_time_s)
        self.history: list[Evaluation] = []
        self._cache: dict[tuple, Evaluation] = {}
        self.on_eval: Callable[[Evaluation], None] | None = None
        self.start_evaluations: dict[str, Evaluation] = {}

    def experiment(self, gains: PidGains, label: str = "candidate") -> Experiment:
        """The closed-loop experiment of one PID set (fixed gains, see experiment.py)."""
        sc = fixed_gain_scenario(self.sc, gains, self.settle_s, seed=self.settings.seed)
        return Experiment(label, sc, self.settings.plc, scored_step(self.sc)[0])

    def score(self, gains: PidGains, outcome: Outcome) -> Evaluation:
        s = self.settings
        raw = cost(outcome, s.cost) if outcome.error is None else math.inf
        over = max_overshoot(outcome)
        ms = self.model.ms(gains)
        penalty = max(0.0, over - s.max_overshoot_pct) / max(s.max_overshoot_pct, 0.5)
        penalty += max(0.0, ms - s.max_ms) / s.max_ms
        obj = raw * (1.0 + PENALTY_WEIGHT * penalty)
        if not math.isfinite(obj):
            obj = FAILED_COST
        return Evaluation(gains, raw, obj, over, ms, outcome.error)

    @staticmethod
    def _key(x: np.ndarray) -> tuple:
        return tuple(np.round(x, 12))

    def evaluate_many(self, xs: list[np.ndarray]) -> list[Evaluation]:
        todo = [x for x in xs if self._key(x) not in self._cache]
        exps = [self.experiment(gains_of(x)) for x in todo]
        for x, out in zip(todo, self.executor.map(run_experiment, exps), strict=True):
            ev = self.score(gains_of(x), out)
            ev.outcome = out
            self._cache[self._key(x)] = ev
            self.history.append(ev)
            if self.on_eval is not None:
                self.on_eval(ev)
        return [self._cache[self._key(x)] for x in xs]

    def start_candidates(self) -> dict[str, PidGains]:
        return {"AMIGO (true model)": amigo(self.model.fit), "SIMC (true model)": simc(self.model.fit)}

    @staticmethod
    def _x(g: PidGains) -> np.ndarray:
        return np.log([g.kp, g.tn, max(g.tv, MIN_TV_S)])

    def run(self) -> Result:
        """Evaluate the rule-based starts (in parallel), start from the better one, then Nelder-Mead."""
        starts = self.start_candidates()
        evs = self.evaluate_many([self._x(g) for g in starts.values()])
        self.start_evaluations = dict(zip(starts, evs, strict=True))
        start = min(evs, key=lambda e: e.objective)
        x0 = self._x(start.gains)
        simplex = seed004_simplex(x0, SIMPLEX_EDGE)
        budget = max(0, self.settings.evals - len(self.history))
        self.evaluate_many(list(simplex[1 : 1 + budget]))  # in parallel
        if budget > len(simplex) - 1:
            minimize(
                lambda x: self.evaluate_many([x])[0].objective,
                x0,
                method="Nelder-Mead",
                options={
                    "initial_simplex": simplex,
                    "maxfev": budget + 1,
                    "xatol": 1e-3,
                    "fatol": 1e-6,
                },
            )
        best = min(self.history, key=lambda e: e.objective)
        return Result(best, start, list(self.history), self.settle_s, best.outcome)
