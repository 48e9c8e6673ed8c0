"""FC_FuzzyScalingFromPlant: Ke, Kec and the ec filter from the identified plant (docs/fuzzy.md)."""

from __future__ import annotations

import math

import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app
from tests.test_fuzzy_inference import fuzzy_sources

DECLS = """    sCtrl : ST_ControllerParameter;
    sFz : ST_FuzzyParameter;
    bRun : BOOL;
    bOk : BOOL;
    fRatio : REAL := 1.0;"""
BODY = """  IF bRun THEN
    bOk := FC_FuzzyScalingFromPlant(fEcFilterMaxRatio := fRatio, sCtrlParam := sCtrl, sFuzzyParam := sFz);
    bRun := FALSE;
  END_IF;"""


@pytest.fixture()
def drv() -> ScanDriver:
    return ScanDriver(load_test_app(build_program(DECLS, BODY), extra=fuzzy_sources()))


def run(drv: ScanDriver, **fields: float) -> bool:
    for name, value in fields.items():
        drv.set(f"sCtrl.{name}", value)
    drv.set("bRun", True)
    drv.scan()
    return drv.get("bOk")


NOISE_PP_PER_SIGMA = 5.0  # FC_FuzzyScalingFromPlant: peak-to-peak of the rest window in standard deviations
EC_NOISE_SHARE = 0.25  # ec noise (1 sigma) as a share of one set spacing U / 3


def test_fopdt_identification(drv: ScanDriver) -> None:
    # K = 0.66 degC/%, T = 149 s, L = 15 s, Kp0 = 14.3 %/degC, output 0..100 %, U = 3, no noise measured
    assert run(drv, fKs=0.66, fTg=149.0, fTu=15.0, fKp=14.3, fYMin=0.0, fYMax=100.0)
    headroom = 100.0 / 2.0  # half the output span: the move available from a mid-range operating point
    e_max = headroom / 14.3
    ec_max = 0.66 * headroom / 149.0
    assert drv.get("sFz.fKe") == pytest.approx(3.0 / e_max, rel=1e-5)
    assert drv.get("sFz.fKec") == pytest.approx(3.0 / ec_max, rel=1e-5)
    # no noise: the shortest filter, two control cycles of the default 0.1 s
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(0.2, rel=1e-6)
    assert drv.get("sFz.fSignBand") == 0.0


def test_ec_filter_and_sign_band_follow_the_measured_noise(drv: ScanDriver) -> None:
    noise_pp = 0.5  # degC peak-to-peak at rest
    assert run(drv, fKs=0.66, fTg=149.0, fTu=15.0, fKp=14.3, fYMin=0.0, fYMax=100.0, fTuneNoisePp=noise_pp)
    kec = drv.get("sFz.fKec")
    sigma = noise_pp / NOISE_PP_PER_SIGMA
    tf = kec * sigma / (EC_NOISE_SHARE * 3.0 / 3.0) - 0.1
    assert 0.2 < tf < 15.0, "the case must sit between the two limits"
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(tf, rel=1e-5)
    # the ec noise through that filter is sigma / (Tf + dt): a quarter of one set spacing on EC
    assert kec * sigma / (tf + 0.1) == pytest.approx(EC_NOISE_SHARE * 1.0, rel=1e-5)
    assert drv.get("sFz.fSignBand") == pytest.approx(noise_pp / 2.0, rel=1e-6)


def test_ec_filter_is_capped_at_the_dead_time(drv: ScanDriver) -> None:
    assert run(drv, fKs=0.66, fTg=149.0, fTu=15.0, fKp=14.3, fYMin=0.0, fYMax=100.0, fTuneNoisePp=50.0)
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(15.0, rel=1e-6)


def test_slope_only_identification_uses_the_heating_side_of_a_split_range(drv: ScanDriver) -> None:
    # tangent identification without K, T: ec_max from the tuning step's maximum slope
    assert run(
        drv,
        fKs=0.0,
        fTg=0.0,
        fTu=4.0,
        fVmax=1.2,
        fYTune=60.0,
        fKp=5.0,
        fYMin=-100.0,
        fYMax=100.0,
        fCtrlCycleTime=1.0,
    )
    headroom = 100.0 / 2.0  # half of the heating side 0..100 %, not of the whole -100..100 %
    assert drv.get("sFz.fKe") == pytest.approx(3.0 * 5.0 / headroom, rel=1e-5)
    assert drv.get("sFz.fKec") == pytest.approx(3.0 / (1.2 * headroom / 60.0), rel=1e-5)
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(2.0, rel=1e-6)  # 2 control cycles


def test_a_cooling_tune_scales_from_the_cooling_set(drv: ScanDriver) -> None:
    # seed 000 kind: only the cooling set was tuned (negative step), the heating set keeps its default
    assert run(
        drv, fKs=0.445, fTg=1795.0, fTu=57.8, fKp=10.0, fKpCool=34.9, fYTune=-50.0, fYMin=-100.0, fYMax=100.0
    )
    headroom = 100.0 / 2.0  # half of the cooling side -100..0 %
    assert drv.get("sFz.fKe") == pytest.approx(3.0 * 34.9 / headroom, rel=1e-5)
    assert drv.get("sFz.fKec") == pytest.approx(3.0 / (0.445 * headroom / 1795.0), rel=1e-5)


@pytest.mark.parametrize(
    "fields",
    [
        {"fTu": 0.0},
        {"fKp": 0.0},
        {"fKs": 0.0, "fVmax": 0.0},
        {"fTu": math.nan},
        {"fYMax": 0.0, "fYMin": 0.0},
        {"fTuneNoisePp": math.nan},
        {"fYTune": -50.0, "fYMin": 0.0},
    ],
)
def test_missing_identification_changes_nothing(drv: ScanDriver, fields: dict[str, float]) -> None:
    base = {"fKs": 0.66, "fTg": 149.0, "fTu": 15.0, "fKp": 14.3, "fYMin": 0.0, "fYMax": 100.0, "fVmax": 0.0}
    base.update(fields)
    assert not run(drv, **base)
    assert drv.get("sFz.fKe") == 6.0 and drv.get("sFz.fKec") == 60.0 and drv.get("sFz.fEcFilterTime") == 1.0
    assert drv.get("sFz.fSignBand") == 0.0
