"""Independent Python evaluation of the fuzzy gain adapter's inference (the oracle for the ST tests).

Membership functions are evaluated analytically (numpy); the Mamdani inference (min AND, max
aggregation, min implication, centroid) is done by scikit-fuzzy's ControlSystem on the same output
universe as the ST (`nOutputPoints` samples); weighted-average defuzzification by plain numpy.
Rule tables are the presets, written out here a second time from the seeds (not read from the ST).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import pytest

SETS = ("NB", "NM", "NS", "ZO", "PS", "PM", "PB")
GAUSS_HALF_CROSSING = 0.5 / math.sqrt(2.0 * math.log(2.0))
INPUT_POINTS = 2401  # fine antecedent universe: (N - 1) divisible by 6 so triangle corners are nodes

# Rule tables, rows E = NB..PB, columns EC = NB..PB, entries -3 (NB) .. 3 (PB).
PRESETS: dict[str, dict[str, list[list[int]]]] = {
    "textbook": {
        "Kp": [
            [3, 3, 2, 2, 1, 0, 0],
            [3, 3, 2, 1, 1, 0, -1],
            [2, 2, 2, 1, 0, -1, -1],
            [2, 2, 1, 0, -1, -2, -2],
            [1, 1, 0, -1, -1, -2, -2],
            [1, 0, -1, -2, -2, -2, -3],
            [0, 0, -2, -2, -2, -3, -3],
        ],
        "Ki": [
            [-3, -3, -2, -2, -1, 0, 0],
            [-3, -3, -2, -1, -1, 0, 0],
            [-3, -2, -1, -1, 0, 1, 1],
            [-2, -2, -1, 0, 1, 2, 2],
            [-2, -1, 0, 1, 1, 2, 3],
            [0, 0, 1, 1, 2, 3, 3],
            [0, 0, 1, 2, 2, 3, 3],
        ],
        "Kd": [
            [1, -1, -3, -3, -3, -2, 1],
            [1, -1, -3, -2, -2, -1, 0],
            [0, -1, -2, -2, -1, -1, 0],
            [0, -1, -1, -1, -1, -1, 0],
            [0, 0, 0, 0, 0, 0, 0],
            [3, -1, 1, 1, 1, 1, 3],
            [3, 2, 2, 2, 1, 1, 3],
        ],
    },
    "seed000": {
        "Kp": [
            [-3, 3, -2, -2, -3, -1, 0],
            [-3, 3, -1, -1, -2, -2, 0],
            [1, 1, 1, -1, 0, 2, 2],
            [1, 0, 1, 0, 1, 0, 1],
            [2, 2, 0, -2, 1, 1, 1],
            [0, -2, -2, -1, -1, 3, -3],
            [0, -1, -3, -1, -2, 3, -3],
        ],
        "Ki": [
            [-3, -1, -2, -1, -1, 0, 0],
            [-3, -1, -1, -1, 0, 0, 0],
            [-2, -2, -1, -1, 0, -1, -2],
            [-2, -2, 1, 0, 1, -2, -2],
            [-2, -1, 0, -1, -1, -2, -2],
            [0, 0, 0, -2, -1, -1, -3],
            [0, 0, -1, 1, -2, -1, -3],
        ],
        "Kd": [
            [3, 2, 2, 1, 2, 2, 3],
            [3, 2, 2, 1, 2, 1, 2],
            [2, 1, -1, 0, 0, -1, 0],
            [1, -1, 0, 0, 0, -1, 1],
            [0, -1, 0, -1, -1, 1, 2],
            [2, 1, 2, 1, 2, 2, 3],
            [3, 2, 2, 1, 2, 2, 3],
        ],
    },
    "seed003": {
        "Kp": [
            [3, 3, 2, 2, 1, 0, 0],
            [3, 3, 2, 1, 1, 0, -1],
            [2, 2, 1, 1, 0, -1, -1],
            [2, 2, 1, 0, -1, -1, -2],
            [1, 1, 0, -1, -1, -2, -2],
            [1, 0, -1, -2, -2, -2, -3],
            [0, -1, -1, -2, -2, -3, -3],
        ],
        "Ki": [
            [-3, -3, -3, -2, -1, 0, 0],
            [-2, -2, -2, -2, -1, 0, 0],
            [-2, -2, -2, -1, 0, 1, 1],
            [-2, -2, -2, 0, 1, 2, 2],
            [-2, -1, 0, 1, 1, 2, 2],
            [-1, 0, 1, 1, 2, 2, 3],
            [0, 1, 2, 2, 2, 3, 3],
        ],
        "Kd": [
            [1, -1, -1, -2, -2, -2, -1],
            [1, -1, -1, -2, -2, -1, 0],
            [1, -1, -1, -2, -1, -1, 0],
            [0, -1, -1, -1, -1, 0, 1],
            [0, -1, 0, 0, 0, 1, 2],
            [2, 2, 1, 1, 1, 1, 3],
            [3, 2, 2, 1, 1, 2, 3],
        ],
    },
}
OUTPUTS = ("Kp", "Ki", "Kd")


@dataclass(frozen=True)
class FuzzyConfig:
    """The part of ST_FuzzyParameter the inference depends on."""

    universe: float = 3.0
    kind: str = "triangular"  # triangular | gaussian | mixed
    gauss_width: float = GAUSS_HALF_CROSSING
    mix_triangular: int = 1
    defuzz: str = "centroid"  # centroid | weighted
    output_points: int = 61
    out_factor: tuple[float, float, float] = (0.5, 0.5, 0.3)
    preset: str = "textbook"
    rules: tuple = field(default=(), compare=True)  # optional override: ((Kp rows), (Ki rows), (Kd rows))

    def table(self, output: int) -> list[list[int]]:
        if self.rules:
            return [list(r) for r in self.rules[output]]
        return PRESETS[self.preset][OUTPUTS[output]]


def membership(x: np.ndarray | float, k: int, cfg: FuzzyConfig) -> np.ndarray:
    """Degree of membership of x in set k (-3..3), as documented in FC_FuzzyMembership."""
    d = cfg.universe / 3.0
    dist = np.asarray(x, dtype=float) - k * d
    triangle = cfg.kind == "triangular" or (cfg.kind == "mixed" and abs(k) <= cfg.mix_triangular)
    if triangle:
        return np.clip(1.0 - np.abs(dist) / d, 0.0, 1.0)
    sigma = cfg.gauss_width * d
    return np.exp(-0.5 * (dist / sigma) ** 2)


@lru_cache(maxsize=32)
def _control_system(cfg: FuzzyConfig):
    ctrl = pytest.importorskip("skfuzzy.control", reason="scikit-fuzzy (dev extra) is the inference oracle")

    u = cfg.universe
    xin = np.linspace(-u, u, INPUT_POINTS)
    e = ctrl.Antecedent(xin, "e")
    ec = ctrl.Antecedent(xin, "ec")
    for k, name in zip(range(-3, 4), SETS, strict=True):
        e[name] = membership(xin, k, cfg)
        ec[name] = membership(xin, k, cfg)
    consequents = []
    xnorm = np.linspace(-u, u, cfg.output_points)
    for out, factor in zip(OUTPUTS, cfg.out_factor, strict=True):
        c = ctrl.Consequent(np.linspace(-factor, factor, cfg.output_points), "d" + out)
        for k, name in zip(range(-3, 4), SETS, strict=True):
            c[name] = membership(xnorm, k, cfg)
        consequents.append(c)
    rules = []
    for i in range(7):
        for j in range(7):
            cons = [consequents[o][SETS[cfg.table(o)[i][j] + 3]] for o in range(3)]
            rules.append(ctrl.Rule(e[SETS[i]] & ec[SETS[j]], cons))
    return ctrl.ControlSystem(rules)


def rule_strengths(eq: float, ecq: float, cfg: FuzzyConfig) -> np.ndarray:
    """7x7 firing strengths min(mu_E(i), mu_EC(j)) after clipping to the universe."""
    u = cfg.universe
    eq, ecq = min(max(eq, -u), u), min(max(ecq, -u), u)
    mu_e = np.array([float(membership(eq, k, cfg)) for k in range(-3, 4)])
    mu_ec = np.array([float(membership(ecq, k, cfg)) for k in range(-3, 4)])
    return np.minimum(mu_e[:, None], mu_ec[None, :])


def infer(eq: float, ecq: float, cfg: FuzzyConfig) -> tuple[float, float, float]:
    """(dKp, dKi, dKd) for quantised inputs, by scikit-fuzzy (centroid) or numpy (weighted average)."""
    u = cfg.universe
    eq, ecq = min(max(eq, -u), u), min(max(ecq, -u), u)
    if cfg.defuzz == "weighted":
        w = rule_strengths(eq, ecq, cfg)
        out = []
        for o in range(3):
            centres = np.array(cfg.table(o), dtype=float) * (cfg.out_factor[o] / 3.0)
            out.append(float((w * centres).sum() / w.sum()))
        return out[0], out[1], out[2]
    ctrl = pytest.importorskip("skfuzzy.control", reason="scikit-fuzzy (dev extra) is the inference oracle")

    sim = ctrl.ControlSystemSimulation(_control_system(cfg))
    sim.input["e"] = eq
    sim.input["ec"] = ecq
    sim.compute()
    return sim.output["dKp"], sim.output["dKi"], sim.output["dKd"]


def continuous_centroid(eq: float, ecq: float, cfg: FuzzyConfig, points: int = 24001) -> tuple[float, ...]:
    """Same inference with plain numpy on a very fine output grid (the continuous ideal)."""
    w = rule_strengths(eq, ecq, cfg)
    x = np.linspace(-cfg.universe, cfg.universe, points)
    mfs = np.array([membership(x, k, cfg) for k in range(-3, 4)])
    out = []
    for o in range(3):
        cut = np.zeros(7)
        table = np.array(cfg.table(o)) + 3
        for i in range(7):
            for j in range(7):
                cut[table[i, j]] = max(cut[table[i, j]], w[i, j])
        agg = np.max(np.minimum(cut[:, None], mfs), axis=0)
        out.append(float(np.trapezoid(agg * x, x) / np.trapezoid(agg, x)) * cfg.out_factor[o] / cfg.universe)
    return tuple(out)


# --- self-checks of the oracle -------------------------------------------------------------------


def test_triangular_partition_sums_to_one() -> None:
    cfg = FuzzyConfig()
    x = np.linspace(-3, 3, 601)
    total = sum(membership(x, k, cfg) for k in range(-3, 4))
    assert np.allclose(total, 1.0)


def test_single_rule_gives_set_centre() -> None:
    """At a node every input is fully one set: the result is that rule's consequent centre."""
    cfg = FuzzyConfig(preset="seed003")
    for i in range(-3, 4):
        for j in (-3, 0, 3):
            got = infer(float(i), float(j), cfg)
            for o in range(3):
                centre = cfg.table(o)[i + 3][j + 3] * cfg.out_factor[o] / 3.0
                # a clipped edge set (NB/PB) has its centroid inside the universe, not at the corner
                if abs(cfg.table(o)[i + 3][j + 3]) < 3:
                    assert got[o] == pytest.approx(centre, abs=1e-9)


@lru_cache(maxsize=1)
def discretisation_error() -> float:
    """Largest |oracle on nOutputPoints = 61 samples - continuous centroid| over 15 random points per
    membership kind, as a share of the output range (docs/fuzzy.md shows it)."""
    rng = np.random.default_rng(3)
    worst = 0.0
    for kind in ("triangular", "gaussian", "mixed"):
        cfg = FuzzyConfig(kind=kind)
        for _ in range(15):
            e, ec = rng.uniform(-3, 3, 2)
            a, b = infer(e, ec, cfg), continuous_centroid(e, ec, cfg)
            worst = max(
                worst, max(abs(p - q) / (2 * f) for p, q, f in zip(a, b, cfg.out_factor, strict=True))
            )
    return worst


def test_oracle_close_to_continuous_centroid() -> None:
    """scikit-fuzzy on 61 output samples vs the continuous ideal: the discretisation error we document."""
    worst = discretisation_error()
    print(f"oracle (61 samples) vs continuous centroid: max {worst:.2e} of the output range")
    assert worst < 2e-3
