"""Zones on one body: FB_TempController tells the other zones when it changes its heat (bStepping), and a
step test that saw another zone's (bNeighbourStep) publishes its model flagged (bTuneShared, alarm bit 23)."""

from __future__ import annotations

import pytest

from tests.st_helpers import ScanDriver
from tests.test_lib_tuner import TS, Fopdt, tuner_driver

IDLE, PASSIVE, ACTIVE, RESET, MANUAL, TUNE = 0, 1, 2, 3, 4, 5
TUNE_IDLE, TUNE_STEP, TUNE_READY, TUNE_ERROR = 2, 3, 4, 5
STATE_TUNED = 6
TUNE_SHARED_BIT = 1 << 23


@pytest.fixture()
def uut() -> ScanDriver:
    """The tuner tests' controller, stepping its output by 100 % in a step test."""
    drv = tuner_driver()
    drv.set("sPar.fYTune", 100.0)
    return drv


def scan(drv: ScanDriver, plant: Fopdt, mode: int, n: int = 1, neighbour: bool = False) -> list[bool]:
    """n scans in mode with the plant in the loop; the bStepping of each."""
    drv.set("nMode", mode)
    drv.set("fbUut.bNeighbourStep", neighbour)
    out = []
    for _ in range(n):
        drv.set("fbUut.fX", plant.measure())
        drv.scan()
        plant.step(drv.get("fbUut.fY"))
        out.append(bool(drv.get("fbUut.bStepping")))
    return out


def tune(drv: ScanDriver, plant: Fopdt, neighbour_at_s: float | None = None, max_s: float = 3000.0) -> None:
    """TUNE until READY; the neighbour steps for one scan neighbour_at_s after the step test starts."""
    drv.set("fbUut.fW1", 80.0)
    for k in range(int(max_s / TS)):
        scan(drv, plant, TUNE, neighbour=neighbour_at_s is not None and k == round(neighbour_at_s / TS))
        if drv.get("nTuneState") in (TUNE_READY, TUNE_ERROR):
            return
    raise AssertionError("the step test did not end")


def flagged(drv: ScanDriver) -> bool:
    """bTuneShared; while it is set, alarm bit 23 is too."""
    shared = bool(drv.get("fbUut.bTuneShared"))
    assert bool(drv.get("fbUut.dwAlarm") & TUNE_SHARED_BIT) or not shared
    return shared


def acknowledge(drv: ScanDriver, plant: Fopdt, mode: int) -> None:
    drv.set("fbUut.bAckAlarm", True)
    scan(drv, plant, mode, n=2)
    drv.set("fbUut.bAckAlarm", False)


def test_each_heat_step_tells_the_other_zones_once(uut) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0, x0=50.0)
    uut.set("fbUut.fW1", 50.0)
    scan(uut, plant, RESET, n=2)
    assert scan(uut, plant, IDLE, n=3) == [False] * 3, "from one off mode to another moves no heat"
    uut.set("fbUut.fW1", 52.0)
    first = scan(uut, plant, ACTIVE, n=20)
    assert first[0] and not any(first[1:]), "entering ACTIVE from IDLE is one step, holding W none"
    uut.set("fbUut.fW1", 60.0)
    assert scan(uut, plant, ACTIVE, n=5) == [True, False, False, False, False], "a new setpoint"
    uut.set("fbUut.fYManual", 30.0)
    assert scan(uut, plant, MANUAL, n=3) == [True, False, False], "to MANUAL"
    uut.set("fbUut.fYManual", 40.0)
    assert scan(uut, plant, MANUAL, n=3) == [True, False, False], "a new manual output"
    assert scan(uut, plant, ACTIVE, n=3) == [False, False, False], "the bumpless return to ACTIVE"
    assert scan(uut, plant, IDLE, n=3) == [True, False, False], "switching off"
    uut.set("fbUut.fW1", 70.0)
    assert scan(uut, plant, IDLE, n=3) == [False, False, False], "a setpoint without a loop moves no heat"


def test_the_step_test_counts_as_a_step_from_start_to_hand_over(uut) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0)
    uut.set("fbUut.fW1", 80.0)
    steps, states = [], []
    for _ in range(int(3000 / TS)):
        steps += scan(uut, plant, TUNE)
        states.append(uut.get("nTuneState"))
        if states[-1] == TUNE_READY:
            break
    assert states[-1] == TUNE_READY
    assert all(steps), "every call of the step test, rest and step, and the hand-over"
    after = scan(uut, plant, TUNE, n=10)
    assert not any(after), "the tuned loop holding W"
    assert not flagged(uut)


@pytest.mark.parametrize("at_s", [5.0, 60.0])
def test_a_step_test_that_saw_another_zones_step_flags_its_model(uut, at_s) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0)
    tune(uut, plant, neighbour_at_s=at_s)
    assert uut.get("nTuneState") == TUNE_READY
    assert flagged(uut), f"a neighbour's step {at_s} s into the test"
    assert uut.get("nState") == STATE_TUNED, "a warning: the loop runs on"
    assert uut.get("fbUut.fY") > 0.0
    scan(uut, plant, ACTIVE, n=50)
    acknowledge(uut, plant, ACTIVE)
    assert flagged(uut), "acknowledging does not make the model the zone's own"
    scan(uut, plant, RESET, n=2)
    assert flagged(uut), "nor does RESET, which keeps the model"
    scan(uut, plant, IDLE, n=1800)
    tune(uut, plant)
    assert uut.get("nTuneState") == TUNE_READY
    assert not flagged(uut), "a model identified alone clears it"
    acknowledge(uut, plant, TUNE)
    assert not uut.get("fbUut.dwAlarm") & TUNE_SHARED_BIT, "and the latched bit goes with the acknowledgement"


def test_a_neighbours_step_outside_the_step_test_does_not_count(uut) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0)
    scan(uut, plant, IDLE, n=10, neighbour=True)
    tune(uut, plant)
    scan(uut, plant, TUNE, n=20, neighbour=True)
    scan(uut, plant, ACTIVE, n=20, neighbour=True)
    assert not flagged(uut)


def test_a_failed_step_test_keeps_the_flag_of_the_model_still_in_use(uut) -> None:
    plant = Fopdt(k=0.9, t=100.0, l=10.0)
    tune(uut, plant, neighbour_at_s=30.0)
    assert flagged(uut)
    kp = uut.get("sPar.fKp")
    uut.set("fbUut.fW1", plant.measure() - 5.0)  # below X: the step test refuses (error 15)
    scan(uut, plant, IDLE, n=2)
    scan(uut, plant, TUNE, n=20)
    assert uut.get("nTuneState") == TUNE_ERROR
    assert uut.get("sPar.fKp") == kp
    assert flagged(uut)
