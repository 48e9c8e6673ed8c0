"""The model-based setpoint response under model mismatch through Modbus, on the shipped scenarios that run
it beside their PID: the zone tunes on the nominal plant; when the scored step starts, the plant's time
constants (and, where the plant has one that can change, its dead time) are 30 % shorter or longer, so the
model the plan starts from is off by that much. Goals on the true temperature: overshoot <= 2 % and 2 %
settling within 1.5x the bang-hold bound of the changed plant (SHORTFALLS: cases that miss the settling goal,
an expected failure once the overshoot goal has passed). Seed 003's hot end and the n-lag oven have
tests of their own (test_heatup.py, test_heatup_oven.py); the FOPDT's dead time is covered in the library
tests (test_lib_heatup.py). CI runs QUICK; THERMOST_SLOW=1 runs every case."""

from __future__ import annotations

import dataclasses

import pytest

from modbus_bridge.optimise.robustness import plant_model, scored_step
from modbus_bridge.plants.response import PlantModel
from modbus_bridge.scenario import Disturbance, Scenario, load_scenario, resolve_scenario
from tests.slow_cases import skip_unless_slow

from .heatup_step import model_based_step

SCENARIOS = ("seed000_forming_platform", "t1_rrf_hotend", "t4_tclab", "t6_nonlinear_hotend")
SCALES = (0.7, 1.3)
MISMATCH_OVERSHOOT_PCT, MISMATCH_BOUND_RATIO = 2.0, 1.5
QUICK = {("t1_rrf_hotend", "L", 1.3)}
# the settling goal not met yet (the overshoot goal holds in every case): the figures when last measured
SHORTFALLS: dict[tuple[str, str, float], str] = {}
KINDS = {"T": "model_mismatch", "L": "dead_time_mismatch"}


def _changes_dead_time(sc: Scenario) -> bool:
    return hasattr(sc.build_plant(), "set_dead_time") and float(sc.plant_params.get("dead_time_s", 0.0)) > 0.0


def cases():
    for name in SCENARIOS:
        sc = load_scenario(resolve_scenario(name))
        for kind in ("T", "L") if _changes_dead_time(sc) else ("T",):
            for scale in SCALES:
                yield pytest.param(name, kind, scale, id=f"{name}-{kind}x{scale}")


def changed(sc: Scenario, kind: str, scale: float) -> tuple[Scenario, PlantModel]:
    """The scenario with the plant changed at the start of its scored step, and that plant's model."""
    scored, _, _ = scored_step(sc)
    zone = sc.zones[0]
    phases = list(zone.phases)
    step = phases[scored]
    phases[scored] = dataclasses.replace(step, disturbances=[Disturbance(KINDS[kind], 0.0, scale),
                                                             *step.disturbances])
    sc = dataclasses.replace(sc, zones=[dataclasses.replace(zone, phases=phases), *sc.zones[1:]])
    pm = plant_model(sc)
    params = ({**pm.params, "time_constant_scale": scale} if kind == "T"
              else {**pm.params, "dead_time_s": float(pm.params["dead_time_s"]) * scale})
    return sc, PlantModel(pm.model, params, pm.channel)


@pytest.mark.parametrize(("name", "kind", "scale"), list(cases()))
def test_the_model_based_step_meets_the_mismatch_goals(harness, name, kind, scale):
    if (name, kind, scale) not in QUICK:
        skip_unless_slow(f"{name} {kind} x{scale}")
    sc, pm = changed(load_scenario(resolve_scenario(name)), kind, scale)
    step = model_based_step(harness, sc, f"{name} {kind} x{scale}", true_plant=pm)
    assert step.overshoot_pct <= MISMATCH_OVERSHOOT_PCT
    within = step.settling_s <= MISMATCH_BOUND_RATIO * step.bound_s
    why = SHORTFALLS.get((name, kind, scale))
    if why is not None:
        assert not within, f"{name} {kind} x{scale} now meets the settling goal: take it out of SHORTFALLS"
        pytest.xfail(f"known shortfall: {why}")
    assert within
