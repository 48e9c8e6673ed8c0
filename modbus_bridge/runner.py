"""Run a scenario end to end: register map + zone bindings, the PLC (embedded soft-PLC, stepped or
real time, or an external PLC at HOST:PORT), one run per controller variant, metrics and reports.
"""

from __future__ import annotations

import asyncio
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from .analysis import PhaseMetrics, run_metrics
from .binding import ControllerCodes, ZoneBinding, resolve_zone
from .client import PlcClient
from .loop import ProgressFn, RunResult, close_loop
from .regmap import RegisterMap, load_register_map
from .reset import FactoryState, reset_to_known_state
from .scenario import Scenario


@dataclass
class HarnessSetup:
    """What a run needs besides the scenario: the program, its register map, the enum codes."""

    regmap: RegisterMap
    codes: ControllerCodes
    program: str | None = None  # ST text for the embedded soft-PLC (None: the project bundle)
    startup_s: float = 0.0
    notes: list[str] = field(default_factory=list)
    factory: FactoryState | None = None

    @staticmethod
    def default() -> HarnessSetup:
        return HarnessSetup(regmap=load_register_map(), codes=ControllerCodes.load())

    def bindings(self, scenario: Scenario) -> dict[int, ZoneBinding]:
        return {z.plc_zone: resolve_zone(self.regmap, z.plc_zone) for z in scenario.zones}

    def program_text(self) -> str:
        if self.program is None:
            from plc.bundle import bundle_text

            self.program = bundle_text()
        return self.program

    def factory_state(self) -> FactoryState:
        """The application's register values after its first scans (a reference copy of the program)."""
        if self.factory is None:
            self.factory = FactoryState.of_program(self.program_text(), self.regmap)
        return self.factory


def parse_host_port(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--plc expects HOST:PORT, got {text!r}")
    return host, int(port)


async def _reset_controllers(
    client: PlcClient,
    scenario: Scenario,
    setup: HarnessSetup,
    bindings: dict[int, ZoneBinding],
    stepped: bool,
) -> None:
    """A known state before a run on a PLC that may have run before (reset.py)."""
    factory = setup.factory_state()
    await reset_to_known_state(client, scenario, bindings, setup.codes, factory, stepped=stepped)


async def run_variants(
    scenario: Scenario,
    setup: HarnessSetup,
    *,
    plc: str | None = None,
    realtime: bool = False,
    speed: float = 1.0,
    progress: ProgressFn | None = None,
    max_plant_time_s: float | None = None,
) -> list[tuple[RunResult, list[PhaseMetrics]]]:
    """One run per variant; with the embedded soft-PLC each variant gets a freshly loaded program."""
    bindings = setup.bindings(scenario)
    runs: list[tuple[RunResult, list[PhaseMetrics]]] = []

    async def reset_and_run(client: PlcClient, variant, stepped: bool) -> RunResult:
        # the application takes its parameter registers from the controller on its first scan:
        # reset (and scan) before the scenario writes anything
        await _reset_controllers(client, scenario, setup, bindings, stepped)
        return await close_loop(
            scenario,
            variant,
            client,
            bindings,
            setup.codes,
            realtime=not stepped,
            speed=speed,
            progress=progress,
            max_plant_time_s=max_plant_time_s,
        )

    for variant in scenario.variants:
        if plc is not None:
            host, port = parse_host_port(plc)
            async with PlcClient(host, port, setup.regmap, name="PLC") as client:
                result = await reset_and_run(client, variant, await client.stepped())
        else:
            from plc.runtime.server import SoftPlc

            t0 = time.perf_counter()
            text = setup.program_text()
            async with SoftPlc(text, host="127.0.0.1", port=0, stepped=not realtime) as soft:
                setup.startup_s += time.perf_counter() - t0
                async with PlcClient("127.0.0.1", soft.port, setup.regmap, name="soft-PLC") as client:
                    result = await reset_and_run(client, variant, stepped=not realtime)
        runs.append((result, run_metrics(result)))
    return runs


class ProgressBar:
    """A one-line progress bar on stderr (plant time done / planned)."""

    WIDTH = 30

    def __init__(self, label: str, stream=sys.stderr) -> None:
        self.label, self.stream = label, stream
        self.enabled = True

    def __call__(self, done: float, total: float) -> None:
        if not self.enabled or total <= 0:
            return
        frac = min(1.0, done / total)
        filled = int(self.WIDTH * frac)
        self.stream.write(
            f"\r{self.label} [{'#' * filled}{'.' * (self.WIDTH - filled)}] {done:6.0f}/{total:.0f} s"
        )
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _child_run(scenario: Scenario, setup: HarnessSetup, index: int, queue, kwargs: dict) -> None:
    """One variant in a forked process; progress and the result (or the exception) go through `queue`."""
    import dataclasses

    def progress(done: float, total: float) -> None:
        queue.put(("progress", index, done, total))

    try:
        single = dataclasses.replace(scenario, variants=[scenario.variants[index]])
        plot_dir = kwargs.pop("plot_dir", None)
        runs = asyncio.run(run_variants(single, setup, progress=progress, **kwargs))
        result = runs[0][0]
        if plot_dir is not None:  # draw in parallel too
            from .report import slug, write_plot

            path = Path(plot_dir) / f"plot_{slug(result.variant.name)}.png"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_plot(result, path)
            result.plot_path = str(path)
        queue.put(("result", index, runs[0]))
    except BaseException as exc:  # noqa: BLE001 - handed to the parent, which re-raises it
        queue.put(("error", index, exc))


def run_variants_parallel(
    scenario: Scenario,
    setup: HarnessSetup,
    *,
    progress: ProgressFn | None = None,
    max_plant_time_s: float | None = None,
    plot_dir: Path | None = None,
) -> list[tuple[RunResult, list[PhaseMetrics]]]:
    """Variants on the embedded stepped soft-PLC, one forked process each (they share nothing: every
    process loads its own soft-PLC), so a side-by-side comparison costs the wall time of one run on a
    multi-core machine. Falls back to sequential runs where fork is unavailable."""
    import multiprocessing as mp

    if len(scenario.variants) < 2 or "fork" not in mp.get_all_start_methods():
        return asyncio.run(
            run_variants(scenario, setup, progress=progress, max_plant_time_s=max_plant_time_s)
        )
    setup.program_text()  # bundle once, before forking
    setup.factory_state()
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    kwargs = {"max_plant_time_s": max_plant_time_s, "plot_dir": plot_dir}
    procs = [
        ctx.Process(target=_child_run, args=(scenario, setup, i, queue, kwargs), daemon=True)
        for i in range(len(scenario.variants))
    ]
    t0 = time.perf_counter()
    for p in procs:
        p.start()
    results: dict[int, tuple[RunResult, list[PhaseMetrics]]] = {}
    done = [0.0] * len(procs)
    total = [0.0] * len(procs)
    error: BaseException | None = None
    try:
        while len(results) + (error is not None) < len(procs) and error is None:
            kind, index, *payload = queue.get()
            if kind == "progress":
                done[index], total[index] = payload
                if progress is not None:
                    progress(sum(done), sum(total))
            elif kind == "result":
                results[index] = payload[0]
            else:
                error = payload[0]
    finally:
        for p in procs:
            p.join(timeout=0.5 if error is None else 0.0)
            if p.is_alive():
                p.terminate()
    if error is not None:
        raise error
    setup.startup_s = time.perf_counter() - t0 - max(r.wall_s for r, _ in results.values())
    return [results[i] for i in range(len(procs))]


@dataclass
class FleetJob:
    """One scenario variant on one PLC (HOST:PORT), for `run_fleet`."""

    scenario: Scenario
    plc: str
    variant_index: int = 0


async def run_fleet(jobs: list[FleetJob], setup: HarnessSetup, *, speed: float = 1.0) -> list[RunResult]:
    """Several PLCs at once on one event loop: one connection per PLC, each job closes its own loop
    (stepped when the PLC offers the soft-PLC control block, else real time)."""

    async def one(job: FleetJob) -> RunResult:
        host, port = parse_host_port(job.plc)
        bindings = setup.bindings(job.scenario)
        async with PlcClient(host, port, setup.regmap, name=f"PLC {job.plc}") as client:
            stepped = await client.stepped()
            await _reset_controllers(client, job.scenario, setup, bindings, stepped)
            return await close_loop(
                job.scenario,
                job.scenario.variants[job.variant_index],
                client,
                bindings,
                setup.codes,
                realtime=not stepped,
                speed=speed,
            )

    return list(await asyncio.gather(*(one(j) for j in jobs)))
