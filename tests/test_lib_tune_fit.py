"""FB_TuneFitNLag's rule for a lag longer than its record, on noise-free first-order records written into the
self-tuner's history: up to three records the lag is fitted; beyond, only while the record departs from its
least-squares straight line by more than twice the noise peak-to-peak (and never beyond ten records); the
threshold is met from both sides with the record's own line residual."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app

HIST_POINTS = 64  # T_TuneHistory
COUNT = 47  # entries recorded
SPACING_S = 1.6
DELAY_S = 4.0
GAIN_C = 400.0  # the step's whole rise, degC
CURVE_NOISE_RATIO = 2.0  # FB_TuneFitNLag's fCurveNoiseRatio
LAG_MATCH = 0.05  # a fitted lag within 5 % of the record's
TIMES_S = SPACING_S * np.arange(1, COUNT + 1)  # when each entry was recorded, s after the step
RECORD_S = COUNT * SPACING_S - DELAY_S  # the record after the delay

DECLS = """    aHist : T_TuneHistory;
    bRun : BOOL;
    bOk : BOOL;
    fNoisePp : REAL;
    fTangent : REAL;
    fKs : REAL;
    fTu : REAL;
    fTg : REAL;
    nOrder : INT;
    fLag : REAL;
    fRatio : REAL;
    fDelay : REAL;
    fRms : REAL;
    fbFit : FB_TuneFitNLag;"""

BODY = f"""  IF bRun THEN
    fbFit(bStart := TRUE, nBudget := 0, fTuTangent := fTangent, fStart := 0.0, fSpacing := {SPACING_S},
          nCount := {COUNT}, fDeltaY := 100.0, fNoisePp := fNoisePp, aHist := aHist);
    bOk := fbFit.bOk;
    fKs := fbFit.fKs;
    fTu := fbFit.fTu;
    fTg := fbFit.fTg;
    nOrder := fbFit.nOrder;
    fLag := fbFit.fLag;
    fRatio := fbFit.fRatio;
    fDelay := fbFit.fDelay;
    fRms := fbFit.fRmsPercent;
    bRun := FALSE;
  END_IF;"""


@pytest.fixture(scope="module")
def app():
    return load_test_app(build_program(DECLS, BODY))


def record(lag_s: float) -> np.ndarray:
    return GAIN_C * (1.0 - np.exp(-np.clip(TIMES_S - DELAY_S, 0.0, None) / lag_s))


def line_rms(r: np.ndarray) -> float:
    """rms residual of the least-squares line through the entries after the delay."""
    keep = TIMES_S > DELAY_S
    coef = np.polyfit(TIMES_S[keep], r[keep], 1)
    return float(np.sqrt(np.mean((r[keep] - np.polyval(coef, TIMES_S[keep])) ** 2)))


def fit(app, r: np.ndarray, noise_pp: float) -> ScanDriver:
    drv = ScanDriver(app)
    for k in range(HIST_POINTS):
        drv.set(f"aHist[{k}]", float(r[k]) if k < COUNT else 0.0)
    drv.set("fNoisePp", noise_pp)
    drv.set("fTangent", DELAY_S)
    drv.set("bRun", True)
    drv.scan()
    return drv


@pytest.mark.parametrize("records", [2.0, 5.0])
def test_a_lag_the_record_bends_for_is_fitted(app, records: float) -> None:
    lag = records * RECORD_S
    r = record(lag)
    drv = fit(app, r, noise_pp=line_rms(r) / (1.5 * CURVE_NOISE_RATIO))
    assert drv.get("bOk")
    assert drv.get("nOrder") == 1
    assert drv.get("fLag") == pytest.approx(lag, rel=LAG_MATCH)


def test_a_lag_beyond_three_records_is_refused_when_its_bend_is_within_the_noise(app) -> None:
    r = record(5.0 * RECORD_S)
    drv = fit(app, r, noise_pp=line_rms(r) / (0.5 * CURVE_NOISE_RATIO))
    assert not drv.get("bOk")
    assert drv.get("nOrder") == 0 and drv.get("fTg") == 0.0


def test_within_three_records_the_noise_does_not_decide(app) -> None:
    r = record(2.0 * RECORD_S)
    drv = fit(app, r, noise_pp=line_rms(r) / (0.5 * CURVE_NOISE_RATIO))
    assert drv.get("bOk") and drv.get("nOrder") == 1


def test_a_lag_beyond_ten_records_is_refused_however_clear_its_bend(app) -> None:
    r = record(12.0 * RECORD_S)
    assert line_rms(r) > 0.1, "the record bends"
    drv = fit(app, r, noise_pp=0.0)
    assert not drv.get("bOk") and drv.get("nOrder") == 0
    assert math.isfinite(drv.get("fRms"))
