"""The adapter inside the OpenPLC application (P_ThermoST, its zone block FB_TempZone),
driven through its registers like an HMI / the harness would."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.st_helpers import REPO_ROOT, ScanDriver, library_sources
from tests.test_fuzzy_inference import fuzzy_sources
from tests.test_lib_tuner import Fopdt

APP_DIR = REPO_ROOT / "plc" / "app"
ACTIVE = 2
TS = 0.1


@pytest.fixture()
def plc() -> ScanDriver:
    try:
        from plc.st.compiler import load_application
    except ImportError as exc:
        pytest.skip(f"soft-PLC compiler not available: {exc}")
    lib = library_sources() + fuzzy_sources()
    sources = lib + [
        ("plc/app/Config0.st", (APP_DIR / "Config0.st").read_text()),
        ("P_ThermoST.st", (APP_DIR / "P_ThermoST.st").read_text()),
    ]
    drv = ScanDriver(load_application(sources))
    drv.scan()
    return drv


def close_loop(drv: ScanDriver, plant: Fopdt, seconds: float, log: list | None = None) -> None:
    for _ in range(round(seconds / TS)):
        drv.set("fPvZone1", plant.measure())
        drv.set("nPvSeqZone1", drv.get("nPvSeqZone1") + 1)  # PV heartbeat
        drv.scan()
        plant.step(drv.get("fYZone1"))
        if log is not None:
            log.append(
                (
                    drv.get("fFuzzyKpZone1"),
                    drv.get("fFuzzyKpRatioZone1"),
                    drv.get("fKpZone1"),
                    drv.get("fFuzzyRule1StrengthZone1"),
                )
            )


def test_registers_in_reserved_block(plc: ScanDriver) -> None:
    fuzzy = [v for v in plc.app.located if "fuzzy" in v.name.lower()]
    assert fuzzy
    for v in fuzzy:
        if v.area == "M":
            assert v.size == "D" and 200 <= v.index <= 299, v.name
        else:
            assert v.area == "Q" and v.index == 4, v.name
    names = {v.name for v in fuzzy}
    assert {"bFuzzyZone1", "bFuzzyZone2", "fFuzzyKpZone1", "fFuzzyTnZone2", "nFuzzyErrorIdZone1"} <= names


def test_adapter_switchable_per_zone_and_explained(plc: ScanDriver) -> None:
    plant = Fopdt(k=3.4, t=140.0, l=5.5, dt=TS)  # RRF default hot end (reference/control.md)
    plc.set("fSetpointZone1", 200.0)
    plc.set("nModeZone1", ACTIVE)
    plc.set("bFuzzyZone1", True)
    log: list = []
    close_loop(plc, plant, 240.0, log)
    kp = np.array([r[0] for r in log])
    base = plc.get("fFuzzyKpBaseZone1")
    assert base == pytest.approx(3.7)
    assert np.ptp(kp) > 0.1 * base  # gains move
    assert kp.min() >= 0.5 * base - 1e-4 and kp.max() <= 1.5 * base + 1e-4
    assert all(r[2] == r[0] for r in log)  # the controller's Kp register shows the effective gain
    assert plc.get("nFuzzyStatusZone1") & 4  # query table ready
    assert 0.0 < plc.get("fFuzzyRule1StrengthZone1") <= 1.0
    code = plc.get("nFuzzyRule1Zone1")
    assert 0 <= code // 10 <= 6 and 0 <= code % 10 <= 6
    assert plc.get("fFuzzyKpZone2") == plc.get("fKpZone2")  # zone 2 untouched (adapter off)
    assert plc.get("fFuzzyKpRatioZone2") == 1.0
    # switch off: back to the tuner's set
    plc.set("bFuzzyZone1", False)
    close_loop(plc, plant, 60.0)
    assert plc.get("fKpZone1") == pytest.approx(base)
    assert plc.get("nFuzzyStatusZone1") & 1 == 0


def test_bad_parameters_over_modbus_keep_base_set(plc: ScanDriver) -> None:
    plant = Fopdt(k=3.4, t=140.0, l=5.5, dt=TS)
    plc.set("fSetpointZone1", 200.0)
    plc.set("nModeZone1", ACTIVE)
    plc.set("bFuzzyZone1", True)
    close_loop(plc, plant, 30.0)
    plc.set("fFuzzyKeZone1", -1.0)
    plc.set("bFuzzyLoadZone1", True)
    close_loop(plc, plant, 1.0)
    assert plc.get("bFuzzyLoadZone1") is False  # self-resetting
    assert plc.get("nFuzzyErrorIdZone1") == 1 and plc.get("nFuzzyStatusZone1") & 2
    assert plc.get("fKpZone1") == pytest.approx(3.7) and plc.get("fTnZone1") == pytest.approx(44.0)
    assert math.isfinite(plc.get("fYZone1"))
    plc.set("fFuzzyKeZone1", 6.0)
    # rule mailbox: dKi rule (E = PS, EC = NM) := 7 -> rejected on load
    plc.set("nFuzzyRuleValueZone1", 7)
    plc.set("nFuzzyRuleAddrZone1", 100 + 10 * 4 + 1)
    plc.set("bFuzzyLoadZone1", True)
    close_loop(plc, plant, 1.0)
    assert plc.get("nFuzzyRuleAddrZone1") == -1
    assert plc.get("nFuzzyErrorIdZone1") == 2
    assert plc.get("fKpZone1") == pytest.approx(3.7)
    plc.set("nFuzzyRuleValueZone1", 1)
    plc.set("nFuzzyRuleAddrZone1", 100 + 10 * 4 + 1)
    plc.set("bFuzzyLoadZone1", True)
    close_loop(plc, plant, 1.0)
    assert plc.get("nFuzzyErrorIdZone1") == 0
