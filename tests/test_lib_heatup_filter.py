"""The model-based setpoint response behind the actual-value filter TUNE sizes from the noise
(fTFilterTuned, FB_TempController on the soft-PLC): the response reads X as TUNE did, unfiltered, so the
PID compares its path with X through the same filter, and its integrator starts from the holding power.
On seed 003's hot end with the model exact and a 2 s filter, the output along the path is the holding
power. Against an unfiltered path the filter's lag on the rising X (its time constant times the slope)
read as X behind the path and pushed the output up by Kp TF dX/dt; the preset at the switch, bumpless on
that push, then left the integrator as far below the holding power for the rest of the response (with
the sensor noise of that one call in it as well)."""

from __future__ import annotations

from dataclasses import dataclass

from tests.test_lib_heatup import (
    ACTIVE,
    HORIZON,
    STEP_AT,
    TS,
    W0,
    W1,
    K,
    L,
    T,
    bound_s,
    controller,
    step_figures,
)
from tests.test_lib_tuner import Fopdt

FILTER_S = 2.0  # s, of the order TUNE sizes for 0.2 degC of noise on a hot end
NOISE_C = 0.03  # a live sensor's (the frozen-PV check)
PRESET_TOLERANCE = 1e-3  # %: the integrator right after the switch against the holding power
PATH_OUTPUT_TOLERANCE = 0.25  # %: the output along the path against the holding power
BOUND_RATIO, OVERSHOOT_PCT = 1.05, 0.5
REST_S = 300.0  # s at W0 first: the filter starts from 0 degC and the loop comes to rest behind it


@dataclass
class FilteredStep:
    i_after_switch: float  # the PID's integrator in the first call after the limit phase, %
    y_hold: float  # the response's holding power, %
    path_output_gap: float  # largest |output - holding power| while the path runs, %
    settling_s: float
    overshoot_pct: float


def filtered_step() -> FilteredStep:
    drv = controller(heat_up=True)
    drv.set("sPar.fTFilterTuned", FILTER_S)
    plant = Fopdt(k=K, t=T, l=L, x0=W0, dt=TS, noise=NOISE_C)
    drv.set("fbUut.fW1", W0)
    drv.set("nMode", ACTIVE)
    i_after, y_hold, gap, was_limit = None, 0.0, 0.0, False
    t_s: list[float] = []
    xs: list[float] = []
    start = round(REST_S / TS)
    for n in range(start + round((HORIZON - STEP_AT) / TS)):
        if n == start:
            drv.set("fbUut.fW1", W1)
        drv.set("fbUut.fX", plant.measure())
        drv.set("fbUut.nPvSequence", n + 1)
        drv.scan()
        assert drv.get("nState") == ACTIVE
        active, limit = drv.get("fbUut.fbHeatUp.bActive"), drv.get("fbUut.fbHeatUp.bLimitPhase")
        if active and not limit:
            y_hold = drv.get("fbUut.fbHeatUp.fYHold")
            if was_limit and i_after is None:
                i_after = drv.get("fbUut.fbPid.fI")
            gap = max(gap, abs(drv.get("fbUut.fY") - y_hold))
        was_limit = was_limit or limit
        plant.step(drv.get("fbUut.fY"))
        if n >= start:
            t_s.append((n - start) * TS)
            xs.append(plant.x)
    assert i_after is not None, "no limit phase ended"
    figures = step_figures(t_s, xs, W0, W1, TS)
    return FilteredStep(i_after, y_hold, gap, figures.settling_s, figures.overshoot_pct)


def test_behind_the_tuned_filter_the_path_is_held_at_the_holding_power() -> None:
    res = filtered_step()
    bound = bound_s()
    print(f"seed 003 160->200 degC behind a {FILTER_S} s filter: integrator after the switch "
          f"{res.i_after_switch:.3f} % (holding power {res.y_hold:.3f} %), output along the path at most "
          f"{res.path_output_gap:.3f} % off it; {res.settling_s:.1f} s (bound {bound:.1f} s), "
          f"{res.overshoot_pct:.2f} %")
    assert abs(res.i_after_switch - res.y_hold) <= PRESET_TOLERANCE
    assert res.path_output_gap <= PATH_OUTPUT_TOLERANCE
    assert res.settling_s <= BOUND_RATIO * bound
    assert res.overshoot_pct <= OVERSHOOT_PCT
