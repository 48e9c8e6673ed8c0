"""FB_FuzzyGainAdapter in the soft-PLC: bad input, base-set capture, query table, closed loop.

The closed loop couples the adapter to the library's PID kernel FB_CtrlPid and a first-order-plus-
dead-time plant integrated here in Python (TCLab-like: K = 0.66 degC/%, T = 149 s, L = 15 s).
"""

from __future__ import annotations

import functools
import math
import warnings
from collections import deque
from dataclasses import dataclass

import numpy as np
import pytest

from tests.st_helpers import ScanDriver, build_program, load_test_app
from tests.test_fuzzy_inference import fuzzy_sources
from tests.test_fuzzy_oracle import FuzzyConfig, infer

CYCLE = 0.5  # s, fCtrlCycleTime = fTaskCycleTime in these tests
PLANT_K, PLANT_T, PLANT_L = 0.66, 149.0, 15.0
AMBIENT = 21.0
BASE = {"fKp": 14.3, "fTn": 36.0, "fTv": 6.3, "fTd": 1.6}  # CHR disturbance 0 % for the plant above
OUTPUT_RANGE = 100.0  # %
SETPOINT = 60.0
LOAD_STEP = -15.0  # % of heater power (e.g. a fan), from the middle of the closed-loop run
BUMP_LIMIT = 0.005 * OUTPUT_RANGE  # largest output step a gain change may cause in the closed loop
MAX_OUTPUT_STEP = 0.1  # %, ST_FuzzyParameter.fMaxOutputStep default: the adapter's own |dKp * e| limit

DECLS = """    sCtrl : ST_ControllerParameter;
    sFz : ST_FuzzyParameter;
    fbAd : FB_FuzzyGainAdapter;
    fbPid : FB_CtrlPid;
    bInit : BOOL;
    bEnable : BOOL;
    bLoad : BOOL;
    bPlantScaling : BOOL;
    bScalingOk : BOOL;
    bPresetOk : BOOL;
    bSetRule : BOOL;
    bSetRuleOk : BOOL;
    nRuleOut : INT;
    nRuleE : INT;
    nRuleEc : INT;
    nRuleValue : INT;
    fW : REAL := 60.0;
    fX : REAL := 21.0;
    fY : REAL;"""
BODY = """  IF NOT bInit THEN
    sCtrl.fCtrlCycleTime := 0.5;
    sCtrl.fTaskCycleTime := 0.5;
    sCtrl.fKp := 14.3;
    sCtrl.fTn := 36.0;
    sCtrl.fTv := 6.3;
    sCtrl.fTd := 1.6;
    sCtrl.fKs := 0.66;
    sCtrl.fTu := 15.0;
    sCtrl.fTg := 149.0;
    bPresetOk := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_TEXTBOOK, sRules := sFz.sRules);
    IF bPlantScaling THEN
      bScalingOk := FC_FuzzyScalingFromPlant(fEcFilterMaxRatio := 1.0, sCtrlParam := sCtrl,
                                             sFuzzyParam := sFz);
    END_IF;
    bInit := TRUE;
  END_IF;
  IF bSetRule THEN
    bSetRuleOk := FC_FuzzySetRule(nOutput := nRuleOut, nSetE := nRuleE, nSetEc := nRuleEc,
                                  nValue := nRuleValue, sRules := sFz.sRules);
    bSetRule := FALSE;
  END_IF;
  fbAd(bEnable := bEnable, bLoad := bLoad, fW := fW, fX := fX, sCtrlParam := sCtrl, sFuzzyParam := sFz);
  fbPid(fW := fW, fX := fX, fKp := sCtrl.fKp, fTn := sCtrl.fTn, fTv := sCtrl.fTv, fTd := sCtrl.fTd,
        fYMin := sCtrl.fYMin, fYMax := sCtrl.fYMax, fCycleTime := sCtrl.fCtrlCycleTime,
        bARWOnIPartOnly := sCtrl.bARWOnIPartOnly);
  fY := fbPid.fY;"""


def new_driver(plant_scaling: bool = False, setup=None) -> ScanDriver:
    drv = ScanDriver(load_test_app(build_program(DECLS, BODY), extra=fuzzy_sources()))
    drv.set("bPlantScaling", plant_scaling)
    # these tests pin the tables as printed and the configured ratio bounds; the symmetric use and the
    # Ms bound on top of them are tested in test_fuzzy_robust.py
    drv.set("sFz.bSymmetric", False)
    drv.set("sFz.fMsMax", 0.0)
    if setup:
        setup(drv)
    return drv


def base_set(drv: ScanDriver) -> dict[str, float]:
    return {k: drv.get(f"sCtrl.{k}") for k in BASE}


def assert_on_base(drv: ScanDriver) -> None:
    got = base_set(drv)
    for k, v in BASE.items():
        assert got[k] == pytest.approx(v, rel=1e-6), k


def load(drv: ScanDriver) -> None:
    drv.set("bLoad", True)
    drv.scan()
    drv.set("bLoad", False)


def pid_output_finite_and_moving(drv: ScanDriver, scans: int = 5) -> None:
    values = []
    for i in range(scans):
        drv.set("fX", 59.5 + 0.05 * i)
        drv.scan()
        values.append(drv.get("fY"))
    assert all(math.isfinite(v) for v in values)
    assert len(set(values)) > 1


@pytest.fixture()
def adapting() -> ScanDriver:
    """Adapter enabled with an error, gains already moved away from the base set."""
    drv = new_driver()
    drv.set("bEnable", True)
    drv.set("fX", 59.6)  # e = 0.4 degC -> E = 2.4 with Ke = 6
    drv.scan(60)
    assert not drv.get("fbAd.bError")
    assert abs(drv.get("fbAd.fKpRatio") - 1.0) > 0.05
    return drv


def test_rule_entry_outside_range_keeps_base_set(adapting: ScanDriver) -> None:
    drv = adapting
    for name, value in (
        ("nRuleOut", 1),
        ("nRuleE", 2),
        ("nRuleEc", -1),
        ("nRuleValue", 4),
        ("bSetRule", True),
    ):
        drv.set(name, value)
    drv.scan()
    assert drv.get("bSetRuleOk")
    assert drv.get("fbAd.bError") is False  # not loaded yet: the adapter still uses its validated copy
    load(drv)
    assert drv.get("fbAd.bError") and drv.get("fbAd.nErrorId") == 2
    assert_on_base(drv)
    pid_output_finite_and_moving(drv)
    assert drv.get("fbAd.bError")
    assert_on_base(drv)
    # repair the entry: the adapter resumes after the next load
    drv.set("nRuleValue", 1)
    drv.set("bSetRule", True)
    drv.scan()
    load(drv)
    drv.set("fX", 59.6)
    drv.scan(5)
    assert not drv.get("fbAd.bError")
    assert drv.get("fbAd.fKpRatio") != 1.0


def test_rule_address_outside_table_is_refused(adapting: ScanDriver) -> None:
    drv = adapting
    for name, value in (
        ("nRuleOut", 3),
        ("nRuleE", 0),
        ("nRuleEc", 0),
        ("nRuleValue", 1),
        ("bSetRule", True),
    ):
        drv.set(name, value)
    drv.scan()
    assert not drv.get("bSetRuleOk")
    drv.set("nRuleOut", 0)
    drv.set("nRuleE", -4)
    drv.set("bSetRule", True)
    drv.scan()
    assert not drv.get("bSetRuleOk")


@pytest.mark.parametrize(
    "field,value,error_id",
    [
        ("fKe", 0.0, 1),
        ("fKec", -60.0, 1),
        ("fKe", math.nan, 1),
        ("fOutKp", math.nan, 5),
        ("fKpRatioMin", 1.2, 5),
        ("nOutputPoints", 1, 5),
        ("fUniverse", 0.0, 5),
    ],
)
def test_bad_parameter_keeps_base_set(adapting: ScanDriver, field: str, value: float, error_id: int) -> None:
    drv = adapting
    drv.set(f"sFz.{field}", value)
    drv.scan()
    assert not drv.get("fbAd.bError")  # takes effect on load only
    load(drv)
    assert drv.get("fbAd.bError") and drv.get("fbAd.nErrorId") == error_id
    assert_on_base(drv)
    pid_output_finite_and_moving(drv)
    assert_on_base(drv)


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_nan_input_keeps_base_set_and_recovers(adapting: ScanDriver, value: float) -> None:
    drv = adapting
    drv.set("fX", value)
    drv.scan()
    assert drv.get("fbAd.bError") and drv.get("fbAd.nErrorId") == 3
    assert_on_base(drv)
    drv.set("fX", 59.6)
    drv.scan(3)
    assert not drv.get("fbAd.bError")
    assert all(math.isfinite(drv.get(f"sCtrl.{k}")) for k in BASE)


def test_tuner_write_becomes_new_base(adapting: ScanDriver) -> None:
    drv = adapting
    drv.set("sCtrl.fKp", 7.0)  # as the self-tuner or an HMI would
    drv.scan()
    assert drv.get("fbAd.fKpBase") == pytest.approx(7.0)
    assert drv.get("fbAd.fTnBase") == pytest.approx(
        drv.get("fbAd.fTnEff") * drv.get("fbAd.fKiRatio") / drv.get("fbAd.fKpRatio"), rel=1e-5
    )


def rules_shown(drv: ScanDriver) -> list[float]:
    return [drv.get("fbAd.fDeltaKp"), drv.get("fbAd.fDeltaKi"), drv.get("fbAd.fDeltaKd"),
            *(drv.get(f"fbAd.aRuleStrength[{k}]") for k in range(4))]


def test_disable_returns_smoothly_to_base(adapting: ScanDriver) -> None:
    drv = adapting
    assert any(v != 0.0 for v in rules_shown(drv))
    drv.set("bEnable", False)
    kp = []
    for _ in range(400):
        drv.scan()
        kp.append(drv.get("sCtrl.fKp"))
        assert rules_shown(drv) == [0.0] * 7  # off: the ratios walk back, no rule is evaluated
        if not drv.get("fbAd.bActive"):
            break
    assert not drv.get("fbAd.bActive")
    assert_on_base(drv)
    steps = np.abs(np.diff(kp)) * 0.4  # |dKp * e| with e = 0.4 degC
    assert steps.max() <= 0.1 + 1e-4


def test_bounds_hold_for_extreme_inputs() -> None:
    drv = new_driver()
    drv.set("bEnable", True)
    drv.set("sFz.fKpRatioMin", 0.8)
    drv.set("sFz.fKpRatioMax", 1.1)
    drv.set("sFz.fMaxOutputStep", 0.0)
    drv.scan()
    load(drv)
    rng = np.random.default_rng(7)
    for x in rng.uniform(-50, 150, 200):
        drv.set("fX", float(x))
        drv.scan()
        assert 0.8 - 1e-6 <= drv.get("fbAd.fKpRatio") <= 1.1 + 1e-6
        assert 0.5 - 1e-6 <= drv.get("fbAd.fKiRatio") <= 1.5 + 1e-6
        assert 0.5 - 1e-6 <= drv.get("fbAd.fKdRatio") <= 1.5 + 1e-6


def test_query_table_equals_inference_at_nodes_and_interpolates_between() -> None:
    drv = new_driver()
    drv.set("bEnable", True)
    drv.set("sFz.bQueryTable", True)
    drv.set("sFz.nQueryHalf", 3)
    drv.set("sFz.nQueryCellsPerCycle", 5)
    drv.set("sFz.fEcFilterTime", 0.0)  # ec = -dX/dt exactly, so (E, EC) can be placed at will
    drv.scan()
    load(drv)
    cycles = 0
    while not drv.get("fbAd.bTableReady"):
        drv.scan()
        cycles += 1
        assert cycles < 20
    assert cycles == math.ceil(49 / 5) - 1  # the load scan built the first 5 nodes
    cfg = FuzzyConfig()  # defaults of ST_FuzzyParameter: triangular, U = 3, textbook, Ke = 6, Kec = 60
    ke, kec = 6.0, 60.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        node = {(i, j): infer(float(i), float(j), cfg) for i in range(-3, 4) for j in range(-3, 4)}
    rng = np.random.default_rng(11)
    probes = [(-3.0, 0.0), (1.0, -2.0), (0.0, 0.0), (2.0, 3.0)]
    probes += [tuple(map(float, rng.uniform(-3, 3, 2))) for _ in range(12)]
    for eq, ecq in probes:
        x_now = 60.0 - eq / ke
        drv.set("fX", x_now + ecq / kec * CYCLE)
        drv.scan()
        drv.set("fX", x_now)
        drv.scan()
        e_got, ec_got = drv.get("fbAd.fEq"), drv.get("fbAd.fEcq")
        assert (e_got, ec_got) == pytest.approx((eq, ecq), abs=1e-3)
        i0, j0 = min(max(math.floor(e_got), -3), 2), min(max(math.floor(ec_got), -3), 2)
        ti, tj = e_got - i0, ec_got - j0
        want = [
            (1 - ti) * (1 - tj) * node[(i0, j0)][o]
            + ti * (1 - tj) * node[(i0 + 1, j0)][o]
            + (1 - ti) * tj * node[(i0, j0 + 1)][o]
            + ti * tj * node[(i0 + 1, j0 + 1)][o]
            for o in range(3)
        ]
        got = (drv.get("fbAd.fDeltaKp"), drv.get("fbAd.fDeltaKi"), drv.get("fbAd.fDeltaKd"))
        assert got == pytest.approx(want, abs=1e-4 * 0.6), (eq, ecq)
        if (eq, ecq) in ((-3.0, 0.0), (1.0, -2.0), (0.0, 0.0)):  # nodes: exactly the rule inference
            assert got == pytest.approx(node[(round(eq), round(ecq))], abs=1e-4 * 0.6)


@dataclass
class LoopLog:
    t: list[float]
    x: list[float]
    y: list[float]
    ratios: list[tuple[float, float, float]]
    gains: list[tuple[float, float, float, float]]
    e: list[float]
    ec: list[float]
    pid: list[tuple[float, float, float, bool]]


def run_loop(enable: bool, seconds: float = 1500.0, query: bool = False) -> LoopLog:
    def setup(drv: ScanDriver) -> None:
        drv.set("sFz.bQueryTable", query)

    drv = new_driver(plant_scaling=True, setup=setup)
    drv.set("bEnable", enable)
    delay = deque([0.0] * int(round(PLANT_L / CYCLE)))
    x = AMBIENT
    log = LoopLog([], [], [], [], [], [], [], [])
    y = 0.0
    for k in range(int(seconds / CYCLE)):
        t = k * CYCLE
        drv.set("fX", x)
        drv.set("fW", SETPOINT)
        drv.scan()
        assert drv.get("bScalingOk")
        y = drv.get("fY")
        log.t.append(t)
        log.x.append(x)
        log.y.append(y)
        log.ratios.append((drv.get("fbAd.fKpRatio"), drv.get("fbAd.fKiRatio"), drv.get("fbAd.fKdRatio")))
        log.gains.append(tuple(drv.get(f"sCtrl.{n}") for n in BASE))
        log.e.append(drv.get("fbAd.fE"))
        log.ec.append(drv.get("fbAd.fEc"))
        log.pid.append(
            (drv.get("fbPid.fP"), drv.get("fbPid.fI"), drv.get("fbPid.fD"), drv.get("fbPid.bARWActive"))
        )
        disturbance = LOAD_STEP if t >= seconds / 2 else 0.0
        delay.append(y + disturbance)
        u = delay.popleft()
        x += CYCLE * (PLANT_K * u - (x - AMBIENT)) / PLANT_T
    return log


def gain_caused_steps(log: LoopLog) -> np.ndarray:
    """|Y(k) - Y'(k)| with Y' the PID output of cycle k computed with the gains of cycle k-1
    (FB_CtrlPid's documented law, docs/library.md), for cycles without anti-windup action."""
    out = []
    for k in range(1, len(log.t)):
        if log.pid[k][3] or log.pid[k - 1][3]:
            continue
        kp0, tn0, tv0, td0 = log.gains[k - 1]
        if log.gains[k] == log.gains[k - 1]:
            continue
        e = SETPOINT - log.x[k]
        p_old = kp0 * e
        i_old = log.pid[k - 1][1] + kp0 * CYCLE / tn0 * e
        d_old = td0 / (td0 + CYCLE) * log.pid[k - 1][2] - kp0 * tv0 / (td0 + CYCLE) * (
            log.x[k] - log.x[k - 1]
        )
        y_old = min(max(p_old + i_old + d_old, 0.0), 100.0)
        out.append(abs(log.y[k] - y_old))
    return np.array(out)


def kp_change_steps(log: LoopLog) -> np.ndarray:
    """|dKp * e| per cycle: the output step the adapter's own limit (fMaxOutputStep) bounds."""
    gains = np.array(log.gains)
    return np.abs(np.diff(gains[:, 0])) * np.abs(np.array(log.e[1:]))


@functools.cache
def closed_loops() -> dict[str, LoopLog]:
    """The fixed-PID and the fuzzy run, once per process (docs/fuzzy.md shows their figures)."""
    return {"fixed": run_loop(False), "fuzzy": run_loop(True)}


@pytest.fixture(scope="module")
def loops() -> dict[str, LoopLog]:
    return closed_loops()


def iae(log: LoopLog) -> float:
    return float(np.sum(np.abs(SETPOINT - np.array(log.x))) * CYCLE)


def test_closed_loop_gains_move_within_bounds(loops: dict[str, LoopLog]) -> None:
    ratios = np.array(loops["fuzzy"].ratios)
    assert np.all(ratios >= 0.5 - 1e-6) and np.all(ratios <= 1.5 + 1e-6)
    assert np.ptp(ratios[:, 0]) > 0.1 and np.ptp(ratios[:, 1]) > 0.1  # the gains really move
    gains = np.array(loops["fuzzy"].gains)
    kp = gains[:, 0]
    assert kp.min() >= 0.5 * BASE["fKp"] - 1e-4 and kp.max() <= 1.5 * BASE["fKp"] + 1e-4
    fixed = np.array(loops["fixed"].gains)
    assert np.all(fixed == fixed[0])  # adapter off: the tuner's set, untouched
    print(
        f"IAE fixed {iae(loops['fixed']):.0f}, fuzzy {iae(loops['fuzzy']):.0f} degC*s; "
        f"Kp ratio {ratios[:, 0].min():.2f}..{ratios[:, 0].max():.2f}, "
        f"Ki ratio {ratios[:, 1].min():.2f}..{ratios[:, 1].max():.2f}, "
        f"Kd ratio {ratios[:, 2].min():.2f}..{ratios[:, 2].max():.2f}"
    )


def test_closed_loop_gain_changes_are_bumpless(loops: dict[str, LoopLog]) -> None:
    log = loops["fuzzy"]
    steps = gain_caused_steps(log)
    assert len(steps) > 100
    assert steps.max() <= BUMP_LIMIT
    # the adapter's own guarantee, independent of the PID's integrator compensation
    dkp = kp_change_steps(log)
    assert dkp.max() <= MAX_OUTPUT_STEP + 1e-3
    print(f"largest output step caused by a gain change: {steps.max():.4f} % (|dKp*e| max {dkp.max():.4f} %)")


COOL_BASE = {"fKpCool": 4.0, "fTnCool": 80.0, "fTvCool": 2.0, "fTdCool": 0.5}


def cooling_driver(adapt_cooling: bool = True) -> ScanDriver:
    def setup(drv: ScanDriver) -> None:
        for name, value in COOL_BASE.items():
            drv.set(f"sCtrl.{name}", value)
        drv.set("sFz.bAdaptCoolingSet", adapt_cooling)

    drv = new_driver(setup=setup)
    drv.set("bEnable", True)
    drv.set("fX", 59.6)
    for k in range(60):
        drv.set("fX", 59.6 - 0.002 * k)  # a slow drift, so ec (and the Kd ratio) is not zero
        drv.scan()
    return drv


def test_cooling_set_follows_the_same_ratios() -> None:
    drv = cooling_driver()
    rp, ri, rd = (drv.get(f"fbAd.f{g}Ratio") for g in ("Kp", "Ki", "Kd"))
    assert abs(rp - 1.0) > 0.05 and abs(ri - 1.0) > 0.05
    assert drv.get("sCtrl.fKpCool") == pytest.approx(4.0 * rp, rel=1e-5)
    assert drv.get("sCtrl.fTnCool") == pytest.approx(80.0 * rp / ri, rel=1e-5)
    assert drv.get("sCtrl.fTvCool") == pytest.approx(2.0 * rd / rp, rel=1e-5)
    assert drv.get("sCtrl.fTdCool") == pytest.approx(0.5 * rd / rp, rel=1e-5)
    # bad input: both sets back to their base
    drv.set("fX", math.nan)
    drv.scan()
    assert drv.get("fbAd.bError")
    assert_on_base(drv)
    for name, value in COOL_BASE.items():
        assert drv.get(f"sCtrl.{name}") == pytest.approx(value, rel=1e-6)


def test_cooling_set_untouched_when_not_adapted() -> None:
    drv = cooling_driver(adapt_cooling=False)
    assert abs(drv.get("fbAd.fKpRatio") - 1.0) > 0.05
    for name, value in COOL_BASE.items():
        assert drv.get(f"sCtrl.{name}") == pytest.approx(value, rel=1e-6)
    # a tuner writing a new cooling set is kept (and becomes the new base)
    drv.set("sCtrl.fKpCool", 6.0)
    drv.scan(3)
    assert drv.get("sCtrl.fKpCool") == pytest.approx(6.0)


def test_error_sign_convention_flips_the_fuzzy_inputs() -> None:
    results = {}
    for flip in (False, True):
        drv = new_driver()
        drv.set("bEnable", True)
        drv.set("sFz.bErrorXMinusW", flip)
        drv.scan()
        load(drv)
        drv.set("fX", 59.7)
        drv.scan(3)
        results[flip] = (drv.get("fbAd.fE"), drv.get("fbAd.fEq"), drv.get("fbAd.fDeltaKp"))
    assert results[True][0] == results[False][0]  # e itself is always W - X
    assert results[True][1] == pytest.approx(-results[False][1])
    assert results[True][2] != results[False][2]
