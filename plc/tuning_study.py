"""Self-tuning study: the library's TUNE on FOPDT, double-lag, n-lag and two-unequal-lag plants over
tau = 0.05 ... 0.9.

For each plant FB_TempController tunes itself in the soft-PLC (AUTO rule, step of `STEP_PCT` from
ambient towards `SETPOINT_C`); the set it writes is then judged on the true plant:
- Ms, the maximum sensitivity of the loop (plant x half a sample of hold, FB_CtrlPid's form), and
- the load IAE: the loop settled at the setpoint, then `LOAD_PCT` % of heater power lost at the
  plant input; IAE of the error over `IAE_WINDOW_SUMS` times the plant's total time (T·n + L).
The references are SIMC (PI, tau_c = theta) and AMIGO (PID) computed on a two-point FOPDT fit of the
true plant's step response, run through the same controller and the same load test. The goals
(Astrom & Hagglund's robust range, and "as good as the better reference"): Ms <= `MS_GOAL`, IAE
within `IAE_RATIO_GOAL` of the better reference. `thermost bench` prints the table; the tests hold
the library to it.
"""

from __future__ import annotations

from dataclasses import dataclass

from modbus_bridge.optimise.experiment import PidGains
from modbus_bridge.plants.response import PlantModel
from plc.library_program import ScanDriver, controller_program, load_program

TS = 0.2  # control and task cycle, s
MODE_ACTIVE, MODE_TUNE = 2, 5
TUNE_READY, TUNE_ERROR = 4, 5
AMBIENT_C = 25.0
SETPOINT_C = 100.0
STEP_PCT = 40.0
LOAD_PCT = 10.0
GAIN_C_PER_PCT = 2.0
SETTLE_SUMS = 8.0  # time at the setpoint before the load step, in plant total times
IAE_WINDOW_SUMS = 12.0
MS_GOAL = 1.6
IAE_RATIO_GOAL = 1.1
RULE_NAMES = {0: "AUTO", 1: "CHR", 2: "Cohen-Coon", 3: "SIMC", 4: "AMIGO"}


@dataclass(frozen=True)
class StudyPlant:
    """K e^(-L s) / (T s + 1)^n, K in degC per % of heater power; with a second lag T2 > 0 (order 1),
    K e^(-L s) / ((T s + 1)(T2 s + 1)): a heater block behind its heater and a sensor behind the block."""

    label: str
    time_constant_s: float
    order: int
    dead_time_s: float
    second_lag_s: float = 0.0

    @property
    def total_time_s(self) -> float:
        return self.time_constant_s * self.order + self.second_lag_s + self.dead_time_s

    def plant_model(self) -> PlantModel:
        return PlantModel("transfer_function" if self.second_lag_s > 0.0 else "nlag", self.params())

    def params(self) -> dict:
        if self.second_lag_s > 0.0:
            t1, t2 = self.time_constant_s, self.second_lag_s
            return {
                "num": (GAIN_C_PER_PCT,),
                "den": (t1 * t2, t1 + t2, 1.0),
                "dead_time_s": self.dead_time_s,
                "ambient_c": AMBIENT_C,
            }
        return {
            "gain_c_per_pct": GAIN_C_PER_PCT,
            "time_constant_s": self.time_constant_s,
            "order": float(self.order),
            "dead_time_s": self.dead_time_s,
            "ambient_c": AMBIENT_C,
        }


def _fopdt(tau: float, total_s: float = 100.0) -> StudyPlant:
    return StudyPlant(f"FOPDT tau {tau:g}", total_s * (1.0 - tau), 1, total_s * tau)


PLANTS: tuple[StudyPlant, ...] = (
    *(_fopdt(tau) for tau in (0.05, 0.2, 0.35, 0.6, 0.9)),
    StudyPlant("double lag T 40 L 2", 40.0, 2, 2.0),
    StudyPlant("double lag T 40 L 20", 40.0, 2, 20.0),
    StudyPlant("double lag T 40 L 80", 40.0, 2, 80.0),
    StudyPlant("two lags 95 + 5", 95.0, 1, 0.0, second_lag_s=5.0),
    StudyPlant("two lags 140 + 16.7", 140.0, 1, 0.0, second_lag_s=16.7),
    StudyPlant("3-lag T 20", 20.0, 3, 0.0),
    StudyPlant("6-lag T 20", 20.0, 6, 0.0),
)


@dataclass
class StudyRow:
    plant: StudyPlant
    tau: float  # of the true plant's two-point FOPDT fit
    fit: tuple[float, float, float]  # true plant: K, L, T of that fit
    identified: tuple[float, float, float]  # the tuner's Ks, Tu, Tg
    rule: str
    gains: PidGains
    ms: float
    ms_on_own_model: float  # fMsTuned, what the tuner published
    iae: float
    references: dict[str, tuple[float, float]]  # name -> (Ms, IAE)

    @property
    def best_reference_iae(self) -> float:
        return min(iae for _, iae in self.references.values())

    @property
    def iae_ratio(self) -> float:
        return self.iae / self.best_reference_iae

    @property
    def meets_goals(self) -> bool:
        return self.ms <= MS_GOAL and self.iae_ratio <= IAE_RATIO_GOAL


class _Plant:
    def __init__(self, plant: StudyPlant) -> None:
        from modbus_bridge.plants.base import PlantDisturbance

        self.model = plant.plant_model().build()
        self.dist = PlantDisturbance.for_channels(1)

    def x(self) -> float:
        return self.model.temperatures()[0]

    def step(self, u: float, load_pct: float = 0.0) -> None:
        self.dist.zones[0].load_pct = load_pct
        self.model.step([u], TS, self.dist)


def _driver() -> ScanDriver:
    drv = ScanDriver(load_program(controller_program()))
    for name, value in (
        ("fTaskCycleTime", TS),
        ("fCtrlCycleTime", TS),
        ("fYMin", 0.0),
        ("fYMax", 100.0),
        ("fWMax", 1000.0),
        ("fXMax", 2000.0),
        ("fTempAbsHigh", 2000.0),
        ("fWatchPeriod", 0.0),
        ("fRunawayPeriod", 0.0),
        ("fTuneTimeout", 20000.0),
        ("fFrozenTime", 0.0),  # noise-free plant: no frozen-PV check
    ):
        drv.set(f"sPar.{name}", value)
    return drv


def _close(drv: ScanDriver, plant: _Plant, load_pct: float = 0.0) -> float:
    drv.set("fbUut.fX", plant.x())
    drv.scan()
    plant.step(drv.get("fbUut.fY"), load_pct)
    return plant.x()


def self_tune(plant: StudyPlant) -> tuple[ScanDriver, int]:
    drv, sim = _driver(), _Plant(plant)
    drv.set("sPar.fYTune", STEP_PCT)
    drv.set("nRule", 0)
    drv.set("fbUut.fW1", SETPOINT_C)
    drv.set("nMode", MODE_TUNE)
    for _ in range(int(20_000 / TS)):
        _close(drv, sim)
        state = drv.get("nTuneState")
        if state in (TUNE_READY, TUNE_ERROR):
            return drv, state
    return drv, drv.get("nTuneState")


def load_iae(plant: StudyPlant, gains: PidGains) -> float:
    """IAE (degC s) after a load step, the loop settled at the setpoint with these gains."""
    drv, sim = _driver(), _Plant(plant)
    for name, value in (("fKp", gains.kp), ("fTn", gains.tn), ("fTv", gains.tv), ("fTd", gains.td_s)):
        drv.set(f"sPar.{name}", value)
    drv.set("fbUut.fW1", SETPOINT_C)
    drv.set("nMode", MODE_ACTIVE)
    for _ in range(int(SETTLE_SUMS * plant.total_time_s / TS)):
        _close(drv, sim)
    iae = 0.0
    for _ in range(int(IAE_WINDOW_SUMS * plant.total_time_s / TS)):
        iae += abs(SETPOINT_C - _close(drv, sim, LOAD_PCT)) * TS
    return iae


def study(plant: StudyPlant) -> StudyRow:
    from modbus_bridge.optimise.robustness import amigo, loop_model_of, simc

    model = loop_model_of(plant.plant_model(), SETPOINT_C, TS)
    fit = model.fit

    drv, state = self_tune(plant)
    if state != TUNE_READY:
        raise RuntimeError(f"{plant.label}: TUNE ended in error {drv.get('fbUut.nErrorId')}")
    gains = PidGains(*(drv.get(f"sPar.{n}") for n in ("fKp", "fTn", "fTv", "fTd")))
    references = {}
    for name, ref in (("SIMC", simc(fit)), ("AMIGO", amigo(fit))):  # Td = Tv / 4, as fTuneTd's default
        references[name] = (model.ms(ref), load_iae(plant, ref))
    return StudyRow(
        plant=plant,
        tau=fit.tau,
        fit=(fit.gain, fit.dead_time_s, fit.time_constant_s),
        identified=(drv.get("sPar.fKs"), drv.get("sPar.fTu"), drv.get("sPar.fTg")),
        rule=RULE_NAMES.get(drv.get("nRuleUsed"), "?"),
        gains=gains,
        ms=model.ms(gains),
        ms_on_own_model=drv.get("sPar.fMsTuned"),
        iae=load_iae(plant, gains),
        references=references,
    )


def table(rows: list[StudyRow]) -> list[str]:
    out = [
        f"self-tuning study (AUTO rule; load {LOAD_PCT:g} % at the plant input; goals Ms <= {MS_GOAL}, "
        f"IAE <= {IAE_RATIO_GOAL} x the better of SIMC/AMIGO on the true model)",
        f"  {'plant':22s} {'tau':>5s}  {'true K/L/T':>16s}  {'identified K/L/T':>17s}  {'rule':6s} "
        f"{'Ms':>5s} {'own':>5s} {'IAE':>7s} {'SIMC Ms/IAE':>13s} {'AMIGO Ms/IAE':>13s} {'ratio':>6s}  goals",
    ]
    for r in rows:
        refs = " ".join(f"{ms_:5.2f}/{iae:7.0f}" for ms_, iae in r.references.values())
        out.append(
            f"  {r.plant.label:22s} {r.tau:5.2f}  {r.fit[0]:4.2f}/{r.fit[1]:5.1f}/{r.fit[2]:5.1f}  "
            f"{r.identified[0]:4.2f}/{r.identified[1]:5.1f}/{r.identified[2]:6.1f}  {r.rule:6s} "
            f"{r.ms:5.2f} {r.ms_on_own_model:5.2f} {r.iae:7.0f} {refs} {r.iae_ratio:6.2f}  "
            f"{'met' if r.meets_goals else 'MISSED'}"
        )
    met = sum(r.meets_goals for r in rows)
    out.append(f"  goals met on {met} of {len(rows)} plants; worst Ms {max(r.ms for r in rows):.2f}")
    return out


def run(quick: bool) -> None:
    """`thermost bench`: the whole table (each plant a few seconds of CPU)."""
    del quick  # the study is small enough to run whole
    rows = []
    for plant in PLANTS:
        rows.append(study(plant))
    print("\n".join(table(rows)), flush=True)
