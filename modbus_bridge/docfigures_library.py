"""Figures of docs/library.md (registered in `docfigures.PRODUCERS` when that module is imported)."""

from __future__ import annotations

from .docfigures import producer, tests_on_path


@producer("tuning-study")
def tuning_study() -> str:
    """Every plant of the self-tuning study, as tests/test_lib_tuning_study.py holds it (the same rows: a
    few seconds of CPU each, computed once per process)."""
    tests_on_path()
    from plc.tuning_study import IAE_RATIO_GOAL, MS_GOAL, PLANTS
    from tests.test_lib_tuning_study import SHORTFALLS, study_row

    lines = [
        f"Goals: Ms ≤ {MS_GOAL:g} on the true plant, load IAE ≤ {IAE_RATIO_GOAL:g} × the better of SIMC and "
        f"AMIGO computed on the true plant (`plc/tuning_study.py`, `tests/test_lib_tuning_study.py`; a plant "
        f"below them is an expected failure there):",
        "",
        "| plant | τ | true K / L / T | identified Ks / Tu / Tg | rule | Ms | Ms on own model | "
        "IAE / better reference | SIMC PI's IAE / better reference | goals |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    rows = [study_row(plant) for plant in PLANTS]
    for r in rows:
        simc_iae = r.references["SIMC"][1]
        missed = "**missed** (expected)" if r.plant.label in SHORTFALLS else "**missed**"
        goals = "met" if r.meets_goals else missed
        lines.append(
            f"| {r.plant.label} | {r.tau:.2f} | {r.fit[0]:.2f} / {r.fit[1]:.1f} / {r.fit[2]:.1f} | "
            f"{r.identified[0]:.2f} / {r.identified[1]:.1f} / {r.identified[2]:.1f} | {r.rule} | "
            f"{r.ms:.2f} | {r.ms_on_own_model:.2f} | {r.iae_ratio:.2f} | "
            f"{simc_iae / r.best_reference_iae:.2f} | {goals} |"
        )
    met = sum(r.meets_goals for r in rows)
    lines += ["", f"Goals met on {met} of {len(rows)} plants; worst Ms on the true plant "
              f"{max(r.ms for r in rows):.2f}."]
    return "\n".join(lines) + "\n"


@producer("heatup-oven-band")
def heatup_oven_band() -> str:
    """The oven's model-based step over its grid of lags and gains, as tests/test_lib_heatup_oven_band.py
    holds it (the same cases, computed once per process: about a minute of CPU)."""
    tests_on_path()
    from tests.test_lib_heatup import MISMATCH_BOUND_RATIO, MISMATCH_OVERSHOOT_PCT
    from tests.test_lib_heatup_oven_band import GAINS, LAGS, SHORTFALLS, band_case, meets_goals

    lines = [
        f"Settling (2 %) over that plant's bang-hold bound / overshoot, the oven's step 100 → 150 °C "
        f"planned on its model; bold: outside the mismatch goals ({MISMATCH_OVERSHOOT_PCT:g} % within "
        f"{MISMATCH_BOUND_RATIO:g} × the bound), an expected failure of "
        f"`tests/test_lib_heatup_oven_band.py`:",
        "",
        "| lags \\ gain | " + " | ".join(f"× {g:g}" for g in GAINS) + " |",
        "|---|" + "---|" * len(GAINS),
    ]
    for lags in LAGS:
        cells = []
        for gain in GAINS:
            settling, overshoot, bound = band_case(lags, gain)
            cell = f"{settling / bound:.2f} × / {overshoot:.2f} %"
            cells.append(cell if meets_goals(lags, gain) else f"**{cell}**")
        lines.append(f"| × {lags:g} | " + " | ".join(cells) + " |")
    met = sum(meets_goals(lags, gain) for lags in LAGS for gain in GAINS)
    lines += ["", f"Within the goals on {met} of {len(LAGS) * len(GAINS)} plants; "
              f"{len(SHORTFALLS)} named as known shortfalls."]
    return "\n".join(lines) + "\n"
