"""A setpoint change while the model-based setpoint response's path still runs: the new response starts from
the plant as that path moves it. On a slow plant (FOPDT K 0.44 degC/%, T 1,800 s, L 60 s: seed 000's
platform as TUNE sees it) the response's slope filter is a tenth of T long, so one pulse later it still
shows the pulse's rise; a start that took it for the plant's own motion planned the second step from a
rest far from the plant's and a holding power far from the one the plant needs. The plant here is exactly
its model, so the holding power for the new setpoint is known: (W - ambient) / K."""

from __future__ import annotations

import pytest

from tests.test_lib_heatup import ACTIVE, OVEN_SUPERVISION, TS, controller
from tests.test_lib_tuner import Fopdt

K, T, L = 0.44, 1800.0, 60.0
AMBIENT, W1, W2 = 20.0, 30.0, 40.0
REST_S = 1000.0  # at rest at ambient: longer than the slope filter's settling (5 x T / 10)
HOLD_TOLERANCE_PCT = 1.0  # of output
NOISE = 0.03  # degC: a live sensor (a bit-identical PV is a frozen one)
SECOND_STEP_AFTER_SWITCH_L = 1.5  # the path has reached W1; the response runs until 2 L after the switch


def second_response_holding_power() -> tuple[float, float, bool]:
    drv = controller(True, model=(K, T, L))
    for name, value in OVEN_SUPERVISION.items():  # a slow plant is watched over minutes
        drv.set(f"sPar.{name}", value)
    plant = Fopdt(k=K, t=T, l=L, x0=AMBIENT, dt=TS, noise=NOISE)
    drv.set("fbUut.fW1", AMBIENT)
    drv.set("nMode", ACTIVE)
    n, switched_at, was_limit, stepped = 0, None, False, False
    while n * TS < REST_S + 2000.0:
        if n == round(REST_S / TS):
            drv.set("fbUut.fW1", W1)
        if switched_at is not None and not stepped and n * TS >= switched_at + SECOND_STEP_AFTER_SWITCH_L * L:
            drv.set("fbUut.fW1", W2)
            stepped = True
        drv.set("fbUut.fX", plant.measure())
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("nState") == ACTIVE, \
            f"state {drv.get('nState')} at {n * TS:.1f} s, alarm {drv.get('fbUut.dwAlarm'):#x}"
        limit = drv.get("fbUut.fbHeatUp.bLimitPhase")
        if was_limit and not limit and switched_at is None:
            switched_at = n * TS
        was_limit = limit
        if stepped:
            return drv.get("fbUut.fbHeatUp.fYHold"), drv.get("fbUut.fbHeatUp.fX0"), \
                drv.get("fbUut.fbHeatUp.bActive")
        plant.step(drv.get("fbUut.fY"))
        n += 1
    pytest.fail("the first response never switched")


def test_a_step_while_the_path_runs_plans_from_the_plant_the_path_moves() -> None:
    hold, x0, active = second_response_holding_power()
    need = (W2 - AMBIENT) / K
    print(f"second response: holding power {hold:.2f} % (the plant needs {need:.2f} %), X0 {x0:.3f} degC")
    assert active
    assert x0 == pytest.approx(W1, abs=0.1)
    assert hold == pytest.approx(need, abs=HOLD_TOLERANCE_PCT)
