"""The self-tuning study (plc.tuning_study): what TUNE's AUTO set is worth on the true plant.

Every plant: TUNE ends READY, the set it writes is robust (Ms <= 2 on the true plant, whatever the
identification did) and its Ms on its own model is published; the goals hold: Ms <= 1.6 and load IAE
within 1.1 x the better of SIMC/AMIGO on the true model. A plant that misses them would be listed in
SHORTFALLS as an expected failure stating its figures.
"""

from __future__ import annotations

import pytest

from plc.tuning_study import IAE_RATIO_GOAL, MS_GOAL, PLANTS, study, table

ROBUST_MS = 2.0
SHORTFALLS: dict[str, str] = {}  # plant label -> why its goals are not met yet (none today)


def _cases():
    for plant in PLANTS:
        why = SHORTFALLS.get(plant.label)
        marks = [pytest.mark.xfail(reason=f"known shortfall: {why}", strict=True)] if why else []
        yield pytest.param(plant, marks=marks, id=plant.label.replace(" ", "_"))


@pytest.mark.parametrize("plant", list(_cases()))
def test_auto_tuning_is_robust_and_rejects_loads_like_the_best_rule(plant) -> None:
    row = study(plant)
    print("\n".join(table([row])))
    assert row.rule == "AMIGO"
    assert row.ms <= ROBUST_MS, f"{plant.label}: Ms {row.ms:.2f} on the true plant"
    assert row.ms_on_own_model <= MS_GOAL
    assert row.ms <= MS_GOAL, f"{plant.label}: Ms {row.ms:.2f} > {MS_GOAL}"
    assert row.iae_ratio <= IAE_RATIO_GOAL, f"{plant.label}: IAE {row.iae_ratio:.2f} x the better reference"
