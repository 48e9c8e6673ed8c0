"""FB_FuzzyInference (ST, in the soft-PLC) against the independent oracle of test_fuzzy_oracle.py.

Grid of (E, EC) points per configuration; equal within 1e-4 of the output range.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

from tests.st_helpers import REPO_ROOT, ScanDriver, build_program, library_sources, load_test_app
from tests.test_fuzzy_oracle import FuzzyConfig, infer, rule_strengths

TOLERANCE = 1e-4  # of the output range
KIND_CODE = {"triangular": 0, "gaussian": 1, "mixed": 2}
DEFUZZ_CODE = {"centroid": 0, "weighted": 1}
PRESET_CODE = {"textbook": 0, "seed000": 1, "seed003": 2}


def fuzzy_sources() -> list[tuple[str, str]]:
    """st_lib/fuzzy/*.st, unless tests.st_helpers.library_sources() already includes them."""
    present = {name for name, _ in library_sources()}
    files = sorted((REPO_ROOT / "st_lib/fuzzy").glob("*.st"))
    pairs = [(str(p.relative_to(REPO_ROOT)), p.read_text()) for p in files]
    return [pair for pair in pairs if pair[0] not in present]


DECLS = """    sFz : ST_FuzzyParameter;
    fbInf : FB_FuzzyInference;
    bPrepare : BOOL;
    nKind : INT;
    nDefuzz : INT;
    nPreset : INT;
    bPresetOk : BOOL;
    fE : REAL;
    fEc : REAL;"""
BODY = """  IF bPrepare THEN
    CASE nKind OF
      0: sFz.eMembership := eFUZZY_MF_TRIANGULAR;
      1: sFz.eMembership := eFUZZY_MF_GAUSSIAN;
    ELSE
      sFz.eMembership := eFUZZY_MF_MIXED;
    END_CASE;
    IF nDefuzz = 1 THEN
      sFz.eDefuzz := eFUZZY_DEFUZZ_WEIGHTED;
    ELSE
      sFz.eDefuzz := eFUZZY_DEFUZZ_CENTROID;
    END_IF;
    CASE nPreset OF
      1: bPresetOk := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_SEED000, sRules := sFz.sRules);
      2: bPresetOk := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_SEED003, sRules := sFz.sRules);
    ELSE
      bPresetOk := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_TEXTBOOK, sRules := sFz.sRules);
    END_CASE;
    fbInf(bPrepare := TRUE, sFuzzyParam := sFz);
    bPrepare := FALSE;
  ELSE
    fbInf(bPrepare := FALSE, bDefuzzify := TRUE, fE := fE, fEc := fEc, sFuzzyParam := sFz);
  END_IF;"""


def make_inference_driver() -> ScanDriver:
    """A soft-PLC program around one FB_FuzzyInference, configured through prepare()."""
    return ScanDriver(load_test_app(build_program(DECLS, BODY), extra=fuzzy_sources()))


@functools.cache
def inference_driver() -> ScanDriver:
    """One driver for every user in the process (prepare() sets the whole configuration each time)."""
    return make_inference_driver()


@pytest.fixture(scope="module")
def drv() -> ScanDriver:
    return inference_driver()


def prepare(drv: ScanDriver, cfg: FuzzyConfig) -> None:
    drv.set("nKind", KIND_CODE[cfg.kind])
    drv.set("nDefuzz", DEFUZZ_CODE[cfg.defuzz])
    drv.set("nPreset", PRESET_CODE[cfg.preset])
    for name, value in (
        ("fUniverse", cfg.universe),
        ("fGaussWidth", cfg.gauss_width),
        ("fOutKp", cfg.out_factor[0]),
        ("fOutKi", cfg.out_factor[1]),
        ("fOutKd", cfg.out_factor[2]),
    ):
        drv.set(f"sFz.{name}", value)
    drv.set("sFz.nOutputPoints", cfg.output_points)
    drv.set("sFz.nMixTriangular", cfg.mix_triangular)
    drv.set("bPrepare", True)
    drv.scan()
    assert drv.get("bPresetOk")
    assert drv.get("fbInf.bReady"), drv.get("fbInf.nErrorId")


def st_infer(drv: ScanDriver, e: float, ec: float) -> tuple[float, float, float]:
    drv.set("fE", e)
    drv.set("fEc", ec)
    drv.scan()
    return drv.get("fbInf.fDeltaKp"), drv.get("fbInf.fDeltaKi"), drv.get("fbInf.fDeltaKd")


def grid(universe: float, seed: int) -> list[tuple[float, float]]:
    nodes = np.linspace(-universe, universe, 7)
    rng = np.random.default_rng(seed)
    pts = [(float(a), float(b)) for a in nodes[::2] for b in nodes[::2]]
    pts += [tuple(map(float, rng.uniform(-universe * 1.1, universe * 1.1, 2))) for _ in range(24)]
    return pts


CONFIGS = [
    FuzzyConfig(kind="triangular", preset="seed000"),
    FuzzyConfig(kind="triangular", preset="textbook", output_points=121),
    FuzzyConfig(kind="gaussian", preset="textbook"),
    FuzzyConfig(kind="mixed", preset="seed003", universe=4.0),
    FuzzyConfig(kind="gaussian", preset="seed003", universe=4.0, gauss_width=0.3398, output_points=41),
    FuzzyConfig(kind="triangular", preset="textbook", defuzz="weighted"),
    FuzzyConfig(kind="mixed", preset="seed000", defuzz="weighted", universe=4.0),
]


@functools.cache
def oracle_deviation(cfg: FuzzyConfig) -> tuple[float, tuple[float, float, int]]:
    """Largest |ST - oracle| over grid() as a share of the output range, and where: (E, EC, output).
    docs/fuzzy.md shows these figures (modbus_bridge/docfigures_fuzzy.py)."""
    drv = inference_driver()
    prepare(drv, cfg)
    worst, where = 0.0, (0.0, 0.0, 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for e, ec in grid(cfg.universe, seed=len(cfg.preset) + cfg.output_points):
            got = st_infer(drv, e, ec)
            want = infer(e, ec, cfg)
            for o in range(3):
                err = abs(got[o] - want[o]) / (2.0 * cfg.out_factor[o])
                if err > worst:
                    worst, where = err, (e, ec, o)
    return worst, where


@pytest.mark.parametrize(
    "cfg", CONFIGS, ids=lambda c: f"{c.kind}-{c.preset}-{c.defuzz}-U{c.universe:g}-N{c.output_points}"
)
def test_st_inference_matches_oracle(cfg: FuzzyConfig) -> None:
    worst, (e, ec, o) = oracle_deviation(cfg)
    print(f"{cfg.kind}/{cfg.preset}/{cfg.defuzz}: max |ST - oracle| = {worst:.2e} of the output range")
    assert worst <= TOLERANCE, f"E {e}, EC {ec}, output {o}: {worst:.2e} of the output range"


def test_dominant_rules_are_the_strongest(drv: ScanDriver) -> None:
    cfg = FuzzyConfig(kind="triangular", preset="textbook")
    prepare(drv, cfg)
    e, ec = 0.7, -1.6
    st_infer(drv, e, ec)
    w = rule_strengths(e, ec, cfg)
    best = sorted(((w[i, j], i - 3, j - 3) for i in range(7) for j in range(7)), reverse=True)[:4]
    got = [
        (drv.get(f"fbInf.aRuleStrength[{k}]"), drv.get(f"fbInf.aRuleE[{k}]"), drv.get(f"fbInf.aRuleEc[{k}]"))
        for k in range(4)
    ]
    assert [g[0] for g in got] == pytest.approx([b[0] for b in best], abs=1e-6)
    assert {(g[1], g[2]) for g in got} == {(b[1], b[2]) for b in best}


def test_the_docs_show_these_deviations() -> None:
    """docs/fuzzy.md's oracle table, from the deviations the tests above computed in this process."""
    from modbus_bridge import docfigures

    text = (docfigures.DOCS / "fuzzy.md").read_text(encoding="utf-8")
    assert "<!-- figures:fuzzy-oracle -->" in text
    assert docfigures.render(text, {"fuzzy-oracle"}) == text, (
        "docs/fuzzy.md: figures:fuzzy-oracle disagrees with the code: run `make docs`"
    )
