"""Faults injected at the plant/sensor side with the plant in the loop, everything over Modbus
(modbus_bridge.faults): the alarm bit of the fault's class, detection time and the heater off.

Goals: heater open, sensor detached and heater stuck on detected and the output at 0 within L + 5 s of
the fault (L: the plant's dead time); frozen PV within 30 s; stale PV (the writer stops) within the
watchdog time plus one second. Every fault on seed 003 and T1's heater faults run here; T1's sensor,
frozen and stale cases, seed 000's platform (its tune alone takes about a minute of CPU) and the
weak-heater / falling-off cases run with THERMOST_SLOW=1 (CI time).
"""

from __future__ import annotations

import asyncio
import os

import pytest

from modbus_bridge.faults import run_fault
from modbus_bridge.regmap import load_register_map
from tests.slow_cases import skip_known_shortfall, skip_unless_slow

from .conftest import PLC_ENV

GOAL_AFTER_DEAD_TIME_S = 5.0
FROZEN_GOAL_S = 30.0
PV_TIMEOUT_S = load_register_map()["fPvTimeoutZone1"].meta.default  # the stale-PV watchdog the scenarios keep
STALE_MARGIN_S = 1.0  # allowed past it
STALE_GOAL_S = PV_TIMEOUT_S + STALE_MARGIN_S
FAST_PLANTS = ("seed003_hotend_fuzzy", "t1_rrf_hotend")
SLOW_PLANTS = ("seed000_forming_platform",)
MODEL_FAULTS = ("heater_open", "sensor_detached", "stuck_on")


def goal_s(fault: str, dead_time_s: float) -> float:
    if fault == "frozen_pv":
        return FROZEN_GOAL_S
    if fault == "stale_pv":
        return STALE_GOAL_S
    return dead_time_s + GOAL_AFTER_DEAD_TIME_S


ALL_FAULTS = MODEL_FAULTS + ("frozen_pv", "stale_pv")
QUICK = {("seed003_hotend_fuzzy", f) for f in ALL_FAULTS} | {("t1_rrf_hotend", "heater_open"),
                                                             ("t1_rrf_hotend", "stuck_on")}


# goals the monitor does not meet yet (run with THERMOST_SLOW=1 as expected failures, so a fix shows)
# Bound (the scenario's plant, open loop from rest at 4 degC, output -36.3 %): L + 5 s = 13 s after the
# fault the PV has moved +0.0022 degC (cooler off) or +0.0082 degC (heater stuck at 100 %), below one count of
# the PT100 input (0.03 degC) and the sensor noise (sigma 0.01 degC); one count is reached after about 28 s
# and 20 s. No PV-based check can classify these faults within L + 5 s on this plant.
SEED000_BOUND = ("T about 1,800 s: 13 s after the fault the PV has moved {moved} degC "
                 "(one count 0.03 degC, noise 0.01)")
SHORTFALLS = {
    ("seed000_forming_platform", "heater_open"): SEED000_BOUND.format(moved="0.002") + (
        "; achieved 403.5 s with the fault 120 s after tuning, 138.5 s with it 600 s after"),
    ("seed000_forming_platform", "stuck_on"): SEED000_BOUND.format(moved="0.008") + (
        "; achieved 290 s (output 0 after 100.5 s) with the fault 120 s after tuning, "
        "198 s (output 0 after 44.5 s) 600 s after"),
}


def shortfall(plant: str, fault: str) -> None:
    """Skip (CI) or mark as an expected failure (THERMOST_SLOW=1) a goal known not to be met yet."""
    why = SHORTFALLS.get((plant, fault))
    if why is not None:
        skip_known_shortfall(f"{plant} {fault}", why)


def cases():
    for plant in FAST_PLANTS + SLOW_PLANTS:
        for fault in ALL_FAULTS:
            why = SHORTFALLS.get((plant, fault))
            marks = [] if (plant, fault) in QUICK else [pytest.mark.slow]
            if why:
                marks.append(pytest.mark.xfail(reason=f"known shortfall: {why}", strict=True))
            yield pytest.param(plant, fault, marks=marks)


def check(harness, plant: str, fault: str, settle_s: float = 120.0):
    goal = goal_s(fault, 0.0 if fault in ("frozen_pv", "stale_pv") else 30.0)
    run = asyncio.run(run_fault(plant, fault, harness, plc=os.environ.get(PLC_ENV), settle_s=settle_s,
                                after_s=goal + 5.0))
    assert run.tuned, f"{plant}: the zone did not tune"
    assert run.alarms_before_fault() == 0, f"{plant}: alarm {run.alarms_before_fault():#x} before the fault"
    goal = goal_s(fault, run.dead_time_s)
    det, off = run.detection_s(), run.off_s()
    figures = f"{plant} {fault}: detected {det} s, output 0 after {off} s, goal {goal:.1f} s"
    assert det is not None and det <= goal, figures
    assert off is not None and off <= goal, figures
    return run


@pytest.mark.parametrize(("plant", "fault"), list(cases()))
def test_fault_is_detected_and_the_heater_goes_off(harness, plant, fault):
    shortfall(plant, fault)
    if (plant, fault) not in QUICK:
        skip_unless_slow(f"{plant} {fault}")
    check(harness, plant, fault)


@pytest.mark.parametrize("fault", ["heater_weak", "sensor_falling_off"])
def test_partial_faults_on_seed003(harness, fault):
    shortfall("seed003_hotend_fuzzy", fault)
    skip_unless_slow("weak heater / sensor falling off")
    check(harness, "seed003_hotend_fuzzy", fault)
