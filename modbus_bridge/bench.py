"""Harness benchmark figures (called by `thermost bench`): plant integration cost per step, the default
scenario's wall time in stepped mode including start-up, and the speed-up over real time of each
shipped scenario. Figures are measured, never assumed; a part that cannot run prints why.
"""

from __future__ import annotations

import asyncio
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from .plants import PLANT_MODELS, PlantDisturbance
from .scenario import load_scenario, resolve_scenario, shipped_scenarios

BENCH_DT_S = 0.1
BENCH_STEPS = 2000
QUICK_STEPS = 300
DEFAULT_TARGET_S = 5.0
RUN_REPEATS = 3  # `thermost run` timings: the median of this many
# `python -m plc.cli` would load plc.cli twice (as __main__), so UserError would not be caught
THERMOST_MAIN = "import sys; from plc.cli import main; sys.exit(main(sys.argv[1:]))"


def plant_costs(steps: int) -> dict[str, float]:
    """Microseconds per plant step (dt = 0.1 s, heater at 50 %) for every plant model."""
    out = {}
    for name, cls in PLANT_MODELS.items():
        kwargs = (
            {"gain_c_per_pct": 1.0, "time_constant_s": 20.0, "dead_time_s": 2.0} if name == "fopdt" else {}
        )
        if name == "sopdt":
            kwargs = {
                "gain_c_per_pct": 1.0,
                "time_constant_s": 20.0,
                "time_constant2_s": 5.0,
                "dead_time_s": 2.0,
            }
        if name == "nlag":
            kwargs = {"gain_c_per_pct": 1.0, "time_constant_s": 10.0, "order": 3, "dead_time_s": 2.0}
        if name == "transfer_function":
            kwargs = {"num": (0.5, 1.0), "den": (200.0, 30.0, 1.0), "dead_time_s": 2.0}
        plant = cls(**kwargs)
        dist = PlantDisturbance.for_channels(plant.channels)
        u = [50.0] * plant.channels
        t0 = time.perf_counter()
        for _ in range(steps):
            plant.step(u, BENCH_DT_S, dist)
        out[name] = (time.perf_counter() - t0) / steps * 1e6
    return out


def scenario_speed(name: str) -> tuple[float, float, float, str | None]:
    """(wall s including start-up, plant time s, start-up s, error) of a shipped scenario's first
    variant, stepped, in this process."""
    from .runner import HarnessSetup, run_variants

    t0 = time.perf_counter()
    sc = load_scenario(resolve_scenario(name))
    sc.variants = sc.variants[:1]
    setup = HarnessSetup.default()
    runs = asyncio.run(run_variants(sc, setup))
    wall = time.perf_counter() - t0
    result = runs[0][0]
    return wall, result.plant_time_s, setup.startup_s, result.error


@dataclass
class RunWall:
    """`thermost run` timed several times: wall and CPU time of each run, the exit code and last line of
    the first run that failed (of the last run when all passed)."""

    walls: list[float]
    cpus: list[float]
    code: int
    last: str

    @property
    def wall_s(self) -> float:
        return statistics.median(self.walls)

    @property
    def cpu_s(self) -> float:
        return statistics.median(self.cpus)

    @property
    def spread(self) -> str:
        return f"{len(self.walls)} runs, {min(self.walls):.1f}-{max(self.walls):.1f} s"


def default_run_wall(repeats: int = RUN_REPEATS) -> RunWall:
    """Wall and CPU time of the complete `thermost run` (new process: imports, bundle, soft-PLC start,
    every variant, reports), `repeats` times: one run on a shared machine drifts by a tenth."""
    timed = RunWall([], [], 0, "")
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            before = os.times()
            t0 = time.perf_counter()
            proc = subprocess.run(
                [sys.executable, "-c", THERMOST_MAIN, "run", "--quiet", "--out", tmp],
                capture_output=True,
                text=True,
                check=False,
            )
            timed.walls.append(time.perf_counter() - t0)
            after = os.times()
        timed.cpus.append((after.children_user - before.children_user)
                          + (after.children_system - before.children_system))
        if timed.code == 0:
            timed.code = proc.returncode
            timed.last = ((proc.stderr.strip() or proc.stdout.strip()).splitlines()[-1:] or [""])[0]
    return timed


def run(quick: bool) -> None:
    print("harness (modbus_bridge):")
    for name, us in plant_costs(QUICK_STEPS if quick else BENCH_STEPS).items():
        print(f"  plant integration {name:18s} {us:8.1f} us/step (dt {BENCH_DT_S} s)")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    timed = default_run_wall(1 if quick else RUN_REPEATS)
    met = "target met" if timed.wall_s < DEFAULT_TARGET_S else "target MISSED"
    status = met if timed.code == 0 else f"{met}; the run failed: exit {timed.code}: {timed.last}"
    print(
        f"  `thermost run` (default scenario, all variants, reports): {timed.wall_s:.2f} s wall "
        f"(median of {timed.spread}), {timed.cpu_s:.2f} s CPU, target < {DEFAULT_TARGET_S:.0f} s wall: "
        f"{status} (load average {load:.1f}, {os.cpu_count()} cores)"
    )
    names = [] if quick else [p.stem for p in shipped_scenarios()]
    for name in names:
        try:
            wall, plant_s, startup, error = scenario_speed(name)
        except Exception as exc:  # noqa: BLE001 - a bench reports what it could not measure
            print(f"  scenario {name}: not measured ({type(exc).__name__}: {exc})")
            continue
        note = f"  ERROR {error}" if error else ""
        print(
            f"  scenario {name:26s} {wall:6.2f} s wall incl. {startup:.2f} s start-up, "
            f"{plant_s:7.0f} s plant time, {plant_s / wall:6.0f}x real time (first variant){note}"
        )
    run_panel(quick)
    control_quality(quick)
    maybe_fault_table()


def run_panel(quick: bool) -> None:
    """Operator panel figures (hmi.bench): Modbus requests per poll cycle, poll-to-browser latency,
    server CPU per tab, trend update rate."""
    from hmi.bench import run as run_hmi

    run_hmi(quick)


def _experiments_per_second(executor, experiments) -> float:
    from .optimise.experiment import run_experiment

    t0 = time.perf_counter()
    executor.map(run_experiment, experiments)
    return len(experiments) / (time.perf_counter() - t0)


def control_quality(quick: bool) -> None:
    """Scorecard and optimiser figures: the quick scorecard's wall time, and closed-loop optimiser
    experiments per second on local processes and on a local Dask cluster (2 worker processes)."""
    from pathlib import Path

    from .optimise.executor import DaskExecutor, LocalExecutor
    from .optimise.experiment import PidGains
    from .optimise.search import Optimiser, Settings
    from .scorecard.build import build_card
    from .scorecard.cli import QUICK_EVALS, QUICK_SCENARIOS

    print("scorecard and optimiser (modbus_bridge.scorecard, modbus_bridge.optimise):")
    small = Path(__file__).resolve().parents[1] / "tests" / "harness_fixtures" / "small_fopdt.toml"
    name = str(small) if quick and small.exists() else QUICK_SCENARIOS[0]
    sc = load_scenario(resolve_scenario(name))
    workers = min(2, os.cpu_count() or 1)
    with LocalExecutor(workers) as ex:
        t0 = time.perf_counter()
        card = build_card(sc, ex, QUICK_EVALS)
        wall = time.perf_counter() - t0
    label = "small FOPDT fixture (--quick bench)" if quick else f"`thermost scorecard --quick` ({sc.name})"
    print(
        f"  scorecard {label}: {wall:.1f} s wall, {len(card.rows)} rows, {QUICK_EVALS} optimiser experiments"
    )
    n = 4 if quick else 8
    opt = Optimiser(sc, Settings(evals=n), ex)
    exps = [opt.experiment(PidGains(kp, 20.0, 2.0)) for kp in np.linspace(1.0, 4.0, n)]
    plant_s = opt.settle_s + sum(p.duration_s or 0.0 for p in sc.zones[0].phases if p.mode != "TUNE")
    with LocalExecutor(workers) as ex:
        local = _experiments_per_second(ex, exps)
    try:
        from distributed import LocalCluster
    except ImportError:
        dask = "not measured (the 'distributed' package is not installed: pip install 'thermost[dask]')"
    else:
        with (
            LocalCluster(
                host="127.0.0.1",
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
            ) as cluster,
            DaskExecutor(cluster.scheduler_address) as ex,
        ):
            dask = f"{_experiments_per_second(ex, exps):.2f} experiments/s"
    print(
        f"  optimiser experiments ({sc.name}, {plant_s:.0f} s plant time each, {n} experiments, "
        f"{workers} workers): local processes {local:.2f} experiments/s | Dask LocalCluster {dask} "
        f"(load average {os.getloadavg()[0]:.1f})"
    )


# ---- fault detection (THERMOST_BENCH_FAULTS=1: about 20 closed-loop runs, several minutes) ----

FAULT_ENV = "THERMOST_BENCH_FAULTS"
FAULT_PLANTS = ("seed003_hotend_fuzzy", "t1_rrf_hotend", "seed000_forming_platform")
RRF_DEVIATION_C, RRF_TIME_S = 15.0, 5.0  # RepRapFirmware: model deviation 15 °C for 5 s (control.md)
MARLIN_HYST_C, MARLIN_PERIOD_S = 4.0, 40.0  # Marlin runaway: 4 °C below W for 40 s
MARLIN_MAXTEMP_C = 290.0  # the application's absolute limit stands in for Marlin's MAXTEMP
PRUSA_AFTER_ANOMALY_S = 10.0  # Prusa MK3 thermal model: heating stops 10-12 s after an anomaly (published)
ANOMALY_C = 1.0  # first visible effect: the PV 1 °C away from its value at the fault


def _held(t, cond, hold_s: float, t0: float) -> float | None:
    start = None
    for ti, c in zip(t, cond, strict=True):
        if ti < t0:
            continue
        if c:
            start = ti if start is None else start
            if ti - start >= hold_s:
                return ti - t0
        else:
            start = None
    return None


def firmware_rules(run, sc) -> dict[str, float | None]:
    """RRF / Marlin / Prusa rules evaluated on the PV trace of a fault run (times from the fault, s)."""
    import math

    import numpy as np

    t, pv, y = np.asarray(run.t), np.asarray(run.pv), np.asarray(run.y)
    sp = float(sc.zones[0].phases[0].setpoint_c or 0.0)
    out: dict[str, float | None] = {}
    p = sc.plant_params
    if {"gain_c_per_pct", "time_constant_s", "dead_time_s"} <= set(p):
        k, tau, lag = p["gain_c_per_pct"], p["time_constant_s"], p["dead_time_s"]
        dt = sc.dt_s
        i0 = int(np.searchsorted(t, run.t_fault))
        model = np.full(t.size, np.nan)
        x = pv[i0]
        base = x - k * y[max(i0 - 1, 0)]  # RRF's model is in steady state at the fault
        for i in range(i0, t.size):
            u = y[max(i - round(lag / dt), 0)]
            x += dt / tau * (base + k * u - x)
            model[i] = x
        out["RRF"] = _held(t, np.abs(pv - model) > RRF_DEVIATION_C, RRF_TIME_S, run.t_fault)
    else:
        out["RRF"] = math.nan  # no FOPDT parameters in the scenario
    marlin = (pv < sp - MARLIN_HYST_C) | (pv > MARLIN_MAXTEMP_C)
    out["Marlin"] = _held(t, marlin, MARLIN_PERIOD_S, run.t_fault)
    after = (t >= run.t_fault) & (np.abs(pv - pv[int(np.searchsorted(t, run.t_fault))]) > ANOMALY_C)
    idx = np.flatnonzero(after)
    out["Prusa"] = float(t[idx[0]] - run.t_fault + PRUSA_AFTER_ANOMALY_S) if idx.size else None
    return out


def fault_table() -> None:
    import numpy as np

    from .faults import FAULTS, open_loop_departure, run_fault

    def fmt(v) -> str:
        if v is None:
            return "never"
        return "n/a" if v != v else f"{v:.1f}"

    print("fault detection (s after the fault; off = output 0 for good; peak = true temperature after it;")
    print("  dPV@L+5 = how far an actuator fault moves the true temperature by L + 5 s, open loop from rest")
    print("  at the output before the fault: the most any PV-based check can see by then):")
    print(f"  {'plant':26s} {'fault':19s} {'L':>5s} {'detect':>7s} {'off':>7s} {'peak':>7s} "
          f"{'RRF':>7s} {'Marlin':>7s} {'Prusa':>7s} {'dPV@L+5':>8s}")
    for name in FAULT_PLANTS:
        sc = load_scenario(resolve_scenario(name))
        for fault in FAULTS:
            try:
                run = asyncio.run(run_fault(name, fault, settle_s=120.0, after_s=60.0))
            except Exception as exc:  # noqa: BLE001 - a bench reports what it could not measure
                print(f"  {name:26s} {fault:19s} not measured ({type(exc).__name__}: {exc})")
                continue
            rules = firmware_rules(run, sc)
            bound = "-"
            if fault in ("heater_open", "heater_weak", "stuck_on"):
                t, y = np.asarray(run.t), np.asarray(run.y)
                y0 = float(np.mean(y[(t < run.t_fault) & (t >= run.t_fault - 10.0)]))
                moved = open_loop_departure(name, fault, y0, run.dead_time_s + 5.0)
                bound = f"{moved:+.4f}"
            print(f"  {name:26s} {fault:19s} {run.dead_time_s:5.1f} {fmt(run.detection_s()):>7s} "
                  f"{fmt(run.off_s()):>7s} {run.peak_c():7.1f} {fmt(rules['RRF']):>7s} "
                  f"{fmt(rules['Marlin']):>7s} {fmt(rules['Prusa']):>7s} {bound:>8s}", flush=True)


def maybe_fault_table() -> None:
    if os.environ.get(FAULT_ENV):
        fault_table()
    else:
        print(f"  fault-detection table: set {FAULT_ENV}=1 (about 20 closed-loop runs)")
