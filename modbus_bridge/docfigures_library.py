"""Figures of docs/library.md (registered in `docfigures.PRODUCERS` when that module is imported)."""

from __future__ import annotations

from .docfigures import producer, tests_on_path


@producer("tuning-shortfalls")
def tuning_shortfalls() -> str:
    """The plants of the self-tuning study below its goals: the expected failures of
    tests/test_lib_tuning_study.py, run through the same study (a few seconds of CPU each)."""
    tests_on_path()
    from plc.tuning_study import IAE_RATIO_GOAL, MS_GOAL, PLANTS
    from tests.test_lib_tuning_study import SHORTFALLS, study_row

    lines = [
        f"Goals: Ms ≤ {MS_GOAL:g} on the true plant, load IAE ≤ {IAE_RATIO_GOAL:g} × the better of SIMC and "
        f"AMIGO computed on the true plant. Plants below them (`plc/tuning_study.py`; expected failures of "
        f"`tests/test_lib_tuning_study.py`):",
        "",
        "| plant | τ | true K / L / T | identified Ks / Tu / Tg | rule | Ms | IAE / better reference |",
        "|---|---|---|---|---|---|---|",
    ]
    for plant in PLANTS:
        if plant.label not in SHORTFALLS:
            continue
        r = study_row(plant)
        lines.append(
            f"| {plant.label} | {r.tau:.2f} | {r.fit[0]:.2f} / {r.fit[1]:.1f} / {r.fit[2]:.1f} | "
            f"{r.identified[0]:.2f} / {r.identified[1]:.1f} / {r.identified[2]:.1f} | {r.rule} | "
            f"{r.ms:.2f} | {r.iae_ratio:.2f} |"
        )
    return "\n".join(lines) + "\n"
