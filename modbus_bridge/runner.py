"""Run a scenario end to end: register map + zone bindings, the PLC (embedded soft-PLC, stepped or
real time, or an external PLC at HOST:PORT), one run per controller variant, metrics and reports.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .analysis import PhaseMetrics, run_metrics
from .binding import ControllerCodes, ZoneBinding, resolve_zone
from .client import PlcClient, PlcError
from .loop import ProgressFn, RunResult, StopFn, close_loop
from .regmap import RegisterMap, load_register_map
from .reset import FactoryState, reset_to_known_state
from .scenario import Scenario, Variant


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


ProgressFor = Callable[[int], ProgressFn]  # variant index -> its progress callback


def _not_run(scenario: Scenario, variant: Variant, why: str, realtime: bool) -> RunResult:
    """A variant the harness could not start (the PLC was lost before it): an empty, failed result."""
    return RunResult(scenario=scenario, variant=variant, zones=[], realtime=realtime, error=why)


async def run_variants(
    scenario: Scenario,
    setup: HarnessSetup,
    *,
    plc: str | None = None,
    realtime: bool = False,
    speed: float = 1.0,
    progress_for: ProgressFor | None = None,
    max_plant_time_s: float | None = None,
    should_stop: StopFn | None = None,
) -> list[tuple[RunResult, list[PhaseMetrics]]]:
    """One run per variant; with the embedded soft-PLC each variant gets a freshly loaded program.
    A PLC that cannot be reached before the first variant is an error (PlcError); one lost later ends
    the run: the variants measured so far are kept, the rest are reported as not run."""
    bindings = setup.bindings(scenario)
    runs: list[tuple[RunResult, list[PhaseMetrics]]] = []

    async def reset_and_run(client: PlcClient, index: int, stepped: bool) -> RunResult:
        # the application takes its parameter registers from the controller on its first scan:
        # reset (and scan) before the scenario writes anything
        await _reset_controllers(client, scenario, setup, bindings, stepped)
        return await close_loop(
            scenario,
            scenario.variants[index],
            client,
            bindings,
            setup.codes,
            realtime=not stepped,
            speed=speed,
            progress=progress_for(index) if progress_for else None,
            max_plant_time_s=max_plant_time_s,
            should_stop=should_stop,
        )

    lost: str | None = None
    for index, variant in enumerate(scenario.variants):
        stop = lost or (should_stop() if should_stop else None)
        if stop:
            result = _not_run(scenario, variant, f"not run: {stop}", realtime or plc is not None)
            runs.append((result, []))
            continue
        try:
            if plc is not None:
                host, port = parse_host_port(plc)
                async with PlcClient(host, port, setup.regmap, name="PLC") as client:
                    result = await reset_and_run(client, index, await client.stepped())
            else:
                from plc.runtime.server import SoftPlc

                t0 = time.perf_counter()
                text = setup.program_text()
                async with SoftPlc(text, host="127.0.0.1", port=0, stepped=not realtime) as soft:
                    setup.startup_s += time.perf_counter() - t0
                    async with PlcClient("127.0.0.1", soft.port, setup.regmap, name="soft-PLC") as client:
                        result = await reset_and_run(client, index, stepped=not realtime)
        except PlcError as exc:
            if not runs:
                raise
            lost = str(exc)
            runs.append((_not_run(scenario, variant, lost, True), []))
            continue
        if result.error and not result.interrupted and plc is not None:
            lost = result.error  # the PLC stopped answering: the next variants would wait for it in vain
        runs.append((result, run_metrics(result) if any(z.t for z in result.zones) else []))
    return runs


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
