"""TUNE's model fit spread over task cycles (FB_TuneFitNLag, fTuneFitBudget): the same model whatever the
budget, bounded work per cycle, and a TUNE that holds its step output until the fit ends."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app
from tests.test_lib_tuner import (
    MODE_TUNE,
    RULE_AUTO,
    TUNE_ERROR,
    TUNE_READY,
    EqualLags,
    Fopdt,
    TwoLags,
    identified,
    run_tune,
    tuner_driver,
)

HIST_POINTS = 64
SPACING_S = 2.5
STEP_PCT = 50.0
STAGE_MAX = 17 * 16  # the largest stage: one round of the delay-and-lag search (nDelaySteps x nRefine)
MAX_FIT_CYCLES = 100  # cycles the fit may hold the step for at the budget below (it needs about 15)
OUTPUTS = ("bOk", "fKs", "fTu", "fTg", "nOrder", "fLag", "fRatio", "fDelay", "fRmsPercent", "nEvaluations")

DECLS = """    aHist : T_TuneHistory;
    bStart : BOOL;
    nBudget : DINT;
    fTangent : REAL;
    fbFit : FB_TuneFitNLag;"""
BODY = f"""  fbFit(bStart := bStart, nBudget := nBudget, fTuTangent := fTangent, fStart := 0.0,
        fSpacing := {SPACING_S}, nCount := {HIST_POINTS}, fDeltaY := {STEP_PCT}, fNoisePp := 0.05,
        aHist := aHist);
  bStart := FALSE;"""


def record(kind: str) -> tuple[np.ndarray, float]:
    """A step record (rise in degC at each entry's time) and its inflection tangent's delay, s."""
    t = SPACING_S * np.arange(1, HIST_POINTS + 1)
    rng = np.random.default_rng(5)
    if kind == "FOPDT":
        x = np.clip(t - 8.0, 0.0, None) / 40.0
        rise, tangent = 1.0 - np.exp(-x), 8.0
    elif kind == "3 lags":
        x = np.clip(t - 3.0, 0.0, None) / 25.0
        rise, tangent = 1.0 - np.exp(-x) * (1.0 + x + x * x / 2.0), 3.0 + 25.0 * 0.8
    else:  # two unequal lags, 140 s and 16.7 s, through to about half the final rise
        t1, t2 = 140.0, 16.7
        rise = 1.0 - (t1 * np.exp(-t / t1) - t2 * np.exp(-t / t2)) / (t1 - t2)
        tangent = 10.3  # t* - y(t*)/y'(t*) at the inflection t* = ln(t1/t2) t1 t2 / (t1 - t2)
    return 30.0 * rise + rng.normal(0.0, 0.01, HIST_POINTS), tangent


@pytest.fixture(scope="module")
def app():
    return load_test_app(build_program(DECLS, BODY))


def fit(app, kind: str, budget: int) -> tuple[dict, list[int]]:
    """The fit's outputs and the residuals each call computed."""
    drv = ScanDriver(app)
    rise, tangent = record(kind)
    for k in range(HIST_POINTS):
        drv.set(f"aHist[{k}]", float(rise[k]))
    drv.set("fTangent", tangent)
    drv.set("nBudget", budget)
    drv.set("bStart", True)
    per_call, before = [], 0
    while True:
        drv.scan()
        done = drv.get("fbFit.nEvaluations")
        per_call.append(done - before)
        before = done
        if not drv.get("fbFit.bBusy"):
            return {name: drv.get(f"fbFit.{name}") for name in OUTPUTS}, per_call
        assert len(per_call) < 200, "the fit does not end"


@pytest.mark.parametrize("kind", ["FOPDT", "3 lags", "two lags"])
def test_the_fit_is_the_same_whatever_the_budget(app, kind: str) -> None:
    whole, calls = fit(app, kind, 0)
    assert len(calls) == 1 and whole["bOk"]
    print(f"\n{kind}: order {whole['nOrder']}, ratio {whole['fRatio']:.3f}, "
          f"{whole['nEvaluations']} residuals")
    for budget in (1, 300, 1000):
        spread, per_call = fit(app, kind, budget)
        assert spread == whole, f"budget {budget}"  # bit for bit: the same stages in the same order
        assert len(per_call) > 1
        assert max(per_call) < budget + STAGE_MAX, (budget, per_call)
        print(f"  budget {budget}: {len(per_call)} calls, at most {max(per_call)} residuals in one")


def test_two_lags_are_still_found_when_spread(app) -> None:
    spread, _ = fit(app, "two lags", 300)
    assert spread["nOrder"] == 2 and 0.05 < spread["fRatio"] < 0.2


TWO_LAGS = TwoLags(k=0.6, t1=140.0, t2=16.7, noise=0.2, seed=1)
TUNE_CASES = [(Fopdt(k=2.0, t=23.4, l=10.6), 80.0, 50.0), (EqualLags(2.0, 20.0, 3), 80.0, 50.0),
              (TWO_LAGS, TWO_LAGS.x0 + 0.7 * TWO_LAGS.k * 60.0, 60.0)]
FIT_BUDGET = 200.0


@pytest.mark.parametrize(("plant", "w", "y_tune"), TUNE_CASES, ids=["FOPDT", "3 lags", "two lags"])
def test_a_spread_fit_tunes_the_same_set_and_holds_the_step_meanwhile(plant, w: float, y_tune: float) -> None:
    one_scan, spread = tuner_driver(), tuner_driver()
    run_tune(one_scan, copy.deepcopy(plant), w=w, y_tune=y_tune)
    assert one_scan.get("nTuneState") == TUNE_READY
    outputs: list[float] = []
    spread.set("sPar.fTuneFitBudget", FIT_BUDGET)
    spread.set("sPar.fYTune", y_tune)
    spread.set("nRule", RULE_AUTO)
    spread.set("fbUut.fW1", w)
    spread.set("nMode", MODE_TUNE)
    p = copy.deepcopy(plant)
    while spread.get("nTuneState") != TUNE_READY:
        assert spread.get("nTuneState") != TUNE_ERROR, spread.get("fbUut.nErrorId")
        assert len(outputs) < MAX_FIT_CYCLES
        spread.set("fbUut.fX", p.measure())
        spread.scan()
        p.step(spread.get("fbUut.fY"))
        if spread.get("fbUut.fbTuner.bFitting"):
            outputs.append(spread.get("fbUut.fY"))
    assert identified(spread) == identified(one_scan)
    assert spread.get("sPar.nTuneOrder") == one_scan.get("sPar.nTuneOrder")
    assert spread.get("sPar.fTuneLagRatio") == one_scan.get("sPar.fTuneLagRatio")
    assert len(outputs) > 1 and set(outputs) == {y_tune}  # the step output stays on while the fit runs
    print(f"\nREADY {len(outputs)} cycles after the record ended (budget {FIT_BUDGET:.0f})")
