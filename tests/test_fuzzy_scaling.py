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
    fRatio : REAL := 0.25;"""
BODY = """  IF bRun THEN
    bOk := FC_FuzzyScalingFromPlant(fEcFilterRatio := fRatio, sCtrlParam := sCtrl, sFuzzyParam := sFz);
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


def test_fopdt_identification(drv: ScanDriver) -> None:
    # K = 0.66 degC/%, T = 149 s, L = 15 s, Kp0 = 14.3 %/degC, output 0..100 %, U = 3
    assert run(drv, fKs=0.66, fTg=149.0, fTu=15.0, fKp=14.3, fYMin=0.0, fYMax=100.0)
    headroom = 100.0 / 2.0  # half the output span: the move available from a mid-range operating point
    e_max = headroom / 14.3
    ec_max = 0.66 * headroom / 149.0
    assert drv.get("sFz.fKe") == pytest.approx(3.0 / e_max, rel=1e-5)
    assert drv.get("sFz.fKec") == pytest.approx(3.0 / ec_max, rel=1e-5)
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(0.25 * 15.0, rel=1e-6)


def test_slope_only_identification_and_cooling_span(drv: ScanDriver) -> None:
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
    headroom = 200.0 / 2.0  # half of the -100..100 % span
    assert drv.get("sFz.fKe") == pytest.approx(3.0 * 5.0 / headroom, rel=1e-5)
    assert drv.get("sFz.fKec") == pytest.approx(3.0 / (1.2 * headroom / 60.0), rel=1e-5)
    assert drv.get("sFz.fEcFilterTime") == pytest.approx(2.0, rel=1e-6)  # 2 control cycles > 0.25 * 4 s


@pytest.mark.parametrize(
    "fields",
    [{"fTu": 0.0}, {"fKp": 0.0}, {"fKs": 0.0, "fVmax": 0.0}, {"fTu": math.nan}, {"fYMax": 0.0, "fYMin": 0.0}],
)
def test_missing_identification_changes_nothing(drv: ScanDriver, fields: dict[str, float]) -> None:
    base = {"fKs": 0.66, "fTg": 149.0, "fTu": 15.0, "fKp": 14.3, "fYMin": 0.0, "fYMax": 100.0, "fVmax": 0.0}
    base.update(fields)
    assert not run(drv, **base)
    assert drv.get("sFz.fKe") == 6.0 and drv.get("sFz.fKec") == 60.0 and drv.get("sFz.fEcFilterTime") == 1.0
