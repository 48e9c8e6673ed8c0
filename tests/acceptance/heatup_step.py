"""One model-based step through Modbus, judged against the bang-hold bound of its true plant: shared by the
acceptance tests of the setpoint response on the shipped scenarios."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from modbus_bridge.optimise.robustness import plant_model, scored_step
from modbus_bridge.plants.response import PlantModel, bang_hold_bound
from modbus_bridge.runner import HarnessSetup
from modbus_bridge.scenario import Scenario

from .conftest import run_scenario

VARIANT = "model-based PID"


@dataclass(frozen=True)
class ScoredStep:
    settling_s: float  # 2 % settling of the true temperature
    overshoot_pct: float  # of the true temperature
    bound_s: float  # the bang-hold bound's settling on the true plant, over the same phase

    @property
    def ratio(self) -> float:
        return self.settling_s / self.bound_s


def model_based_step(setup: HarnessSetup, sc: Scenario, label: str, true_plant: PlantModel | None = None
                     ) -> ScoredStep:
    """Run the scenario's model-based variant alone and score its step (the scored phase of zone 1) against
    the bound of `true_plant` (the scenario's plant unless given), computed over that phase."""
    sc = dataclasses.replace(sc, variants=[v for v in sc.variants if v.name == VARIANT])
    assert sc.variants, f"{sc.name}: no variant named {VARIANT!r}"
    [(result, metrics)] = run_scenario(setup, sc)
    assert result.error is None, result.error
    scored, y0, r = scored_step(sc)
    phase = sc.zones[0].phases[scored]
    bound = bang_hold_bound(true_plant or plant_model(sc), y0, r, sc.dt_s, phase.duration_s)
    values = {m.phase: m for m in metrics}[phase.name].values
    step = ScoredStep(values["true_settling_time_2pct_s"], values["true_overshoot_pct"], bound.settling_s)
    print(f"{label}: bound {bound.settling_s:.1f} s (one switch, {bound.overshoot_pct:.2f} %); model-based "
          f"{step.settling_s:.1f} s = {step.ratio:.2f} x, true overshoot {step.overshoot_pct:.2f} %")
    return step
