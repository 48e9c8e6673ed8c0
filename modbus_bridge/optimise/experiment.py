"""Closed-loop experiments for the optimiser and the scorecard, always through the harness (Modbus to the
embedded soft-PLC, or to `--plc HOST:PORT`).

A fixed-gain experiment is the scenario with every TUNE phase replaced by an ACTIVE hold at the tune
setpoint for `settle_s`, the candidate PID set written to the zone's parameter registers at the start
and the fuzzy adapter off; the phases after the (last) TUNE phase are the ones scored, so a fixed set
and the self-tuned controller are judged on the same programme.

Costs (on zone 1 of the scored phases, e = setpoint − PV):
- `iae`: Σ ∫|e| dt;
- `itae`: Σ ∫ (t − t_phase) |e| dt, time counted from each phase start (a step or a disturbance);
- `ramp`: seed 004's F_r = ΣS + a·t_osc + b·E (a = b = 1): S = ∫|e| dt after the PV first meets the
  setpoint (the surface of the oscillations), t_osc = from then to the last exit from the ±band,
  E = |mean e| over the last tenth of the window (the error left).
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..analysis import PhaseMetrics
from ..loop import EFFECTIVE_GAIN_ROLES, RunResult
from ..scenario import Phase, Scenario, Variant, Zone

DERIVATIVE_FILTER_RATIO = 0.25  # Td = Tv / 4, as the project's tuner sets it
COSTS = ("iae", "itae", "ramp")
RAMP_BAND_C = 0.5  # seed 004's oscillation band when the scored window has no setpoint step
BAND_2PCT = 0.02
TAIL_FRACTION = 0.1


@dataclass(frozen=True)
class PidGains:
    kp: float  # %/°C
    tn: float  # s
    tv: float  # s
    td: float | None = None  # s; None -> DERIVATIVE_FILTER_RATIO * tv

    @property
    def td_s(self) -> float:
        return self.td if self.td is not None else DERIVATIVE_FILTER_RATIO * self.tv

    def as_dict(self) -> dict[str, float]:
        return {"kp_pct_per_c": self.kp, "tn_s": self.tn, "tv_s": self.tv, "td_s": self.td_s}


@functools.lru_cache(maxsize=1)
def _setup():
    from ..runner import HarnessSetup

    return HarnessSetup.default()


def gain_writes(zone: int, gains: PidGains, cooling: bool = False) -> dict[str, float]:
    """The registers of one PID set: the heating set, or the cooling set (a zone tuned on its cooling
    side)."""
    from ..binding import resolve_zone

    b = resolve_zone(_setup().regmap, zone)
    roles = ("kp_cool", "tn_cool", "tv_cool", "td_cool") if cooling else ("kp", "tn", "tv", "td")
    return dict(zip((b[r] for r in roles), (gains.kp, gains.tn, gains.tv, gains.td_s), strict=True))


def tunes_cooling(zone: Zone) -> bool:
    """The zone's TUNE steps its output down (a negative step written to its fYTune register with it): it
    tunes the cooling set, which its cooling steps then use."""
    from ..binding import resolve_zone

    y_tune = resolve_zone(_setup().regmap, zone.plc_zone)["y_tune"]
    return any(p.mode == "TUNE" and float(p.writes.get(y_tune, 0.0)) < 0.0 for p in zone.phases)


def last_tune_index(phases: list[Phase]) -> int:
    idx = [i for i, p in enumerate(phases) if p.mode == "TUNE"]
    return idx[-1] if idx else -1


def fixed_gain_scenario(sc: Scenario, gains: PidGains, settle_s: float, seed: int | None = None) -> Scenario:
    zones = []
    for z in sc.zones:
        phases = []
        for i, p in enumerate(z.phases):
            q = dataclasses.replace(p, disturbances=list(p.disturbances), writes=dict(p.writes))
            if p.mode == "TUNE":
                q.mode, q.until, q.timeout_s, q.duration_s, q.end_at_s = "ACTIVE", None, None, settle_s, None
            if q.fuzzy is not None:
                q.fuzzy = False
            if i == 0:
                q.writes.update(gain_writes(z.plc_zone, gains, cooling=tunes_cooling(z)))
            phases.append(q)
        zones.append(dataclasses.replace(z, phases=phases))
    return dataclasses.replace(
        sc,
        zones=zones,
        variants=[Variant(name="fixed PID", fuzzy=False)],
        seed=sc.seed if seed is None else seed,
    )


def variant_scenario(sc: Scenario, index: int, seed: int | None = None) -> Scenario:
    return dataclasses.replace(sc, variants=[sc.variants[index]], seed=sc.seed if seed is None else seed)


@dataclass
class Experiment:
    label: str
    scenario: Scenario
    plc: str | None = None
    scored_from_phase: int = 0  # index of zone 1's first scored phase


@dataclass
class Outcome:
    label: str
    metrics: list[PhaseMetrics]
    t: np.ndarray
    pv: np.ndarray
    true_c: np.ndarray
    setpoint: np.ndarray
    u: np.ndarray  # output applied to the plant, % (a PWM heater: its duty over each step)
    phases: list[tuple[str, float, float]]  # zone 1: name, start, end
    scored_from_phase: int = 0
    y: np.ndarray | None = None  # the controller's output register, % (what a PWM output modulates)
    # the gains the PID ran with (EFFECTIVE_GAIN_ROLES: the set in use, as an adapter left it), per step
    gains: dict[str, np.ndarray] = field(default_factory=dict)
    error: str | None = None
    wall_s: float = 0.0
    plant_time_s: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def scored_start(self) -> float:
        if not self.phases:
            return 0.0
        return self.phases[min(self.scored_from_phase, len(self.phases) - 1)][1]

    def scored_metrics(self) -> list[PhaseMetrics]:
        zone = self.metrics[0].zone if self.metrics else ""
        names = [p[0] for p in self.phases[self.scored_from_phase :]]
        return [m for m in self.metrics if m.zone == zone and m.phase in names]


def run_experiment(exp: Experiment) -> Outcome:
    """One closed-loop run through the harness (module level: runs in a worker process or on Dask)."""
    from ..runner import run_variants

    t0 = time.perf_counter()
    setup = _setup()
    runs = asyncio.run(run_variants(exp.scenario, setup, plc=exp.plc))
    result, metrics = runs[0]
    out = outcome_of(exp.label, result, metrics, exp.scored_from_phase)
    out.wall_s = time.perf_counter() - t0
    return out


def outcome_of(label: str, result: RunResult, metrics: list[PhaseMetrics], scored_from_phase: int) -> Outcome:
    """The outcome of a finished run (zone 1's trace)."""
    tr = result.zones[0]
    return Outcome(
        label=label,
        metrics=metrics,
        t=np.asarray(tr.t),
        pv=np.asarray(tr.pv),
        true_c=np.asarray(tr.true_c),
        setpoint=np.asarray(tr.setpoint),
        u=np.asarray(tr.u),
        phases=[(p.name, p.t_start, p.t_end) for p in tr.phases],
        scored_from_phase=scored_from_phase,
        y=np.asarray(tr.y) if len(tr.y) == len(tr.t) else None,
        gains={
            r: np.asarray(tr.gains[r]) for r in EFFECTIVE_GAIN_ROLES if len(tr.gains.get(r, ())) == len(tr.t)
        },
        error=result.error,
        plant_time_s=result.plant_time_s,
    )


def _window(o: Outcome) -> tuple[np.ndarray, np.ndarray]:
    mask = o.t >= o.scored_start - 1e-9
    return o.t[mask], (o.setpoint - o.pv)[mask]


def cost(o: Outcome, kind: str) -> float:
    if kind not in COSTS:
        raise ValueError(f"unknown cost {kind!r} (one of {', '.join(COSTS)})")
    t, e = _window(o)
    if t.size < 2 or not np.all(np.isfinite(e)):
        return math.inf
    if kind == "iae":
        return float(np.trapezoid(np.abs(e), t))
    if kind == "itae":
        total = 0.0
        for _name, start, end in o.phases[o.scored_from_phase :]:
            m = (t >= start - 1e-9) & (t < end - 1e-9)
            if np.count_nonzero(m) > 1:
                total += float(np.trapezoid((t[m] - start) * np.abs(e[m]), t[m]))
        return total
    # ramp: seed 004's F_r
    sign = np.sign(e)
    met = np.flatnonzero(sign != sign[0])
    start = met[0] if met.size else e.size - 1
    surface = float(np.trapezoid(np.abs(e[start:]), t[start:])) if e.size - start > 1 else 0.0
    sp = o.setpoint[o.t >= o.scored_start - 1e-9]
    jump = float(np.max(np.abs(np.diff(sp)))) if sp.size > 1 else 0.0
    band = max(BAND_2PCT * jump, RAMP_BAND_C) if jump > 1.0 else RAMP_BAND_C
    outside = np.flatnonzero(np.abs(e) > band)
    t_osc = float(t[outside[-1]] - t[start]) if outside.size and outside[-1] > start else 0.0
    tail = max(2, int(TAIL_FRACTION * e.size))
    return surface + t_osc + abs(float(np.mean(e[-tail:])))


def judged(values: dict, key: str) -> float | None:
    """A step's figure as the optimiser and the scorecard judge it: of the true temperature where the run
    recorded it (sensor noise adds its peaks to a PV's and can keep a PV outside a band its process is
    inside), of the measured PV otherwise; None when the step has neither."""
    return values.get(f"true_{key}", values.get(key))


def max_overshoot(o: Outcome) -> float:
    """The largest overshoot of a scored step (`judged`)."""
    vals = [judged(m.values, "overshoot_pct") for m in o.scored_metrics() if m.kind == "step"]
    vals = [v for v in vals if v is not None and math.isfinite(v)]
    return max(vals, default=0.0)
