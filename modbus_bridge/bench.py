"""Harness benchmark figures (called by `thermost bench`): plant integration cost per step, the default
scenario's wall time in stepped mode including start-up, and the speed-up over real time of each
shipped scenario. Figures are measured, never assumed; a part that cannot run prints why.
"""

from __future__ import annotations

import asyncio
import time

from .plants import PLANT_MODELS, PlantDisturbance
from .scenario import DEFAULT_SCENARIO, load_scenario, resolve_scenario, shipped_scenarios

BENCH_DT_S = 0.1
BENCH_STEPS = 2000
QUICK_STEPS = 300
DEFAULT_TARGET_S = 5.0


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
        plant = cls(**kwargs)
        dist = PlantDisturbance.for_channels(plant.channels)
        u = [50.0] * plant.channels
        t0 = time.perf_counter()
        for _ in range(steps):
            plant.step(u, BENCH_DT_S, dist)
        out[name] = (time.perf_counter() - t0) / steps * 1e6
    return out


def scenario_speed(name: str) -> tuple[float, float, float, str | None]:
    """(wall s including start-up, plant time s, start-up s, error) of a shipped scenario, stepped."""
    from .runner import HarnessSetup, run_variants

    t0 = time.perf_counter()
    sc = load_scenario(resolve_scenario(name))
    sc.variants = sc.variants[:1]
    setup = HarnessSetup.default()
    runs = asyncio.run(run_variants(sc, setup))
    wall = time.perf_counter() - t0
    result = runs[0][0]
    return wall, result.plant_time_s, setup.startup_s, result.error


def run(quick: bool) -> None:
    print("harness (modbus_bridge):")
    for name, us in plant_costs(QUICK_STEPS if quick else BENCH_STEPS).items():
        print(f"  plant integration {name:18s} {us:8.1f} us/step (dt {BENCH_DT_S} s)")
    names = [DEFAULT_SCENARIO] if quick else [p.stem for p in shipped_scenarios()]
    for name in names:
        try:
            wall, plant_s, startup, error = scenario_speed(name)
        except Exception as exc:  # noqa: BLE001 - a bench reports what it could not measure
            print(f"  scenario {name}: not measured ({type(exc).__name__}: {exc})")
            continue
        note = f"  ERROR {error}" if error else ""
        target = f" (target < {DEFAULT_TARGET_S:.0f} s)" if name == DEFAULT_SCENARIO else ""
        print(
            f"  scenario {name:34s} {wall:6.2f} s wall incl. {startup:.2f} s start-up{target}, "
            f"{plant_s:7.0f} s plant time, {plant_s / wall:6.0f}x real time (first variant){note}"
        )
