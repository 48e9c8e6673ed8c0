"""`thermost simulate`: a scenario's plant in closed loop with a PLC, in real time (or S x faster), until
Ctrl-C, for a panel, mbpoll, FUXA or Node-RED to attach to.

Without `--plc` the embedded soft-PLC runs the bundle (its TASK interval shortened S times for
`--speed S`) and serves Modbus TCP on 127.0.0.1:PORT (default 5020, as `thermost plc`). With
`--plc HOST:PORT` only the plant runs here, against that PLC (e.g. OpenPLC loaded with
`thermost bundle --speed S`). The plant talks to the PLC only over Modbus, like the harness: every plant
step it writes each zone's PV (or raw counts) and reads the outputs in one block read.

The scenario gives the plant, the sensors and each zone's configuration writes (its first phase's
`write` table); the phase programme itself is not run: the operator drives modes and setpoints.
Lines on standard input inject plant events (`help` lists them), e.g. `fault 1 open`.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .binding import ZoneBinding, resolve_zone
from .client import PlcClient, PlcError
from .loop import raw_sensor_parameters
from .plants import PlantDisturbance
from .regmap import RegisterMap
from .scenario import Scenario
from .sensors import SENSOR_FAULTS

DEFAULT_PORT = 5020
DEFAULT_SCENARIO = "t4_tclab"  # two zones (TCLab twin heater): both application zones have a plant
RETRY_S = 0.5  # pause between reconnection attempts while the PLC does not answer
PV_SEQ_WRAP = 2**31 - 1  # the heartbeat register is a DINT
STARTUP_SCANS = 3  # the application takes its parameters on its first scan: write after it
CATCH_UP_S = 1.0  # wall time the plant makes up after a stall; longer stalls are skipped
HELP = (
    "commands: fault ZONE open|short|none | load ZONE PCT | heater ZONE fail|ok | ambient DELTA_C | "
    "plc off|on (embedded soft-PLC: stop / restart serving) | status | help"
)


@dataclass
class SimZone:
    name: str
    plc_zone: int
    channel: int
    binding: ZoneBinding
    sensor: object
    raw: bool
    pv: float = math.nan
    u: float = 0.0


@dataclass
class PlantSim:
    """The plant side of the loop: one plant, one sensor per zone, disturbances set from outside."""

    scenario: Scenario
    regmap: RegisterMap
    zones: list[SimZone] = field(default_factory=list)

    def __post_init__(self) -> None:
        sc = self.scenario
        self.plant = sc.build_plant()
        self.dist = PlantDisturbance.for_channels(self.plant.channels)
        temps = self.plant.temperatures()
        for i, z in enumerate(sc.zones):
            sensor = z.sensor.build(seed=sc.seed * 1000 + i)
            sensor.reset(temps[z.channel])
            self.zones.append(
                SimZone(z.name, z.plc_zone, z.channel, resolve_zone(self.regmap, z.plc_zone), sensor,
                        sc.pv_path == "raw")
            )
        self.read_names = [z.binding["y"] for z in self.zones]
        self.t = 0.0
        self.pv_seq = 0

    def configuration(self) -> dict:
        """Writes made once: PV path selection, raw sensor constants, each zone's first-phase writes."""
        writes: dict = {}
        for z, spec in zip(self.zones, self.scenario.zones, strict=True):
            for role in ("pv_select", "raw_from_modbus"):
                if z.binding.has(role):
                    writes[z.binding[role]] = z.raw
            if z.raw:
                writes.update(raw_sensor_parameters(z.binding, spec.sensor.adc))
            if spec.phases:
                writes.update(spec.phases[0].writes)
        return writes

    def measure(self, dt: float) -> dict:
        temps = self.plant.temperatures()
        writes: dict = {}
        self.pv_seq = self.pv_seq % PV_SEQ_WRAP + 1
        for z in self.zones:
            z.pv = z.sensor.measure(temps[z.channel], dt)
            if z.raw:
                writes[z.binding["pv_raw"]] = z.sensor.last_counts
            else:
                writes[z.binding["pv"]] = z.pv
            if z.binding.has("pv_seq"):  # heartbeat with every new PV (the PLC's stale-PV watchdog)
                writes[z.binding["pv_seq"]] = self.pv_seq
        return writes

    def apply(self, outputs: dict, dt: float) -> None:
        u = [0.0] * self.plant.channels
        for z in self.zones:
            z.u = float(outputs[z.binding["y"]])
            if not math.isfinite(z.u):
                z.u = 0.0
            u[z.channel] = z.u
        self.plant.step(u, dt, self.dist)
        self.t += dt

    def zone(self, number: str) -> SimZone:
        for z in self.zones:
            if str(z.plc_zone) == number:
                return z
        raise ValueError(f"no zone {number} (zones: {', '.join(str(z.plc_zone) for z in self.zones)})")

    def command(self, line: str) -> str:
        """One stdin command; returns the answer line (errors are answered, never raised)."""
        words = line.split()
        if not words:
            return ""
        try:
            return self._command(words)
        except (ValueError, IndexError) as exc:
            return f"error: {exc or 'missing argument'}; {HELP}"

    def _command(self, w: list[str]) -> str:
        cmd = w[0].lower()
        if cmd == "help":
            return HELP
        if cmd == "status":
            return "; ".join(
                f"zone {z.plc_zone} {z.name}: PV {z.pv:.2f} degC, output {z.u:.1f} %, "
                f"sensor {z.sensor.fault}" for z in self.zones
            ) + f"; plant time {self.t:.1f} s"
        if cmd == "ambient":
            self.dist.ambient_offset_c = float(w[1])
            return f"ambient offset {self.dist.ambient_offset_c:g} degC"
        if cmd in ("fault", "load", "heater"):
            z = self.zone(w[1])
            zd = self.dist.zones[z.channel]
            arg = w[2].lower()
            if cmd == "fault":
                if arg not in SENSOR_FAULTS:
                    raise ValueError(f"sensor fault must be one of {', '.join(SENSOR_FAULTS)}")
                z.sensor.fault = arg
                return f"zone {z.plc_zone} sensor: {arg}"
            if cmd == "load":
                value = float(arg)
                if not math.isfinite(value):
                    raise ValueError("load must be a finite number of %")
                zd.load_pct = value
                return f"zone {z.plc_zone} load: {value:g} %"
            if arg not in ("fail", "ok"):
                raise ValueError("heater fail|ok")
            zd.heater_failed = arg == "fail"
            return f"zone {z.plc_zone} heater: {arg}"
        raise ValueError(f"unknown command {w[0]!r}")


class Simulation:
    """Runs the plant against a PLC at HOST:PORT in real time / speed; survives PLC outages."""

    def __init__(self, sim: PlantSim, host: str, port: int, speed: float,
                 log: Callable[[str], None] = print, catch_up_s: float = CATCH_UP_S) -> None:
        self.sim, self.host, self.port, self.speed, self.log = sim, host, port, speed, log
        self.catch_up_s = catch_up_s
        self.steps = 0
        self.late_steps = 0
        self.connected = False

    async def run(self, stop: asyncio.Event) -> None:
        dt = self.sim.scenario.dt_s
        configured = False
        waiting = False
        while not stop.is_set():
            try:
                async with PlcClient(self.host, self.port, self.sim.regmap, name="PLC") as client:
                    if not configured:
                        await client.write_tags(self.sim.configuration())
                        configured = True
                    if not self.connected:
                        self.log(f"plant connected to the PLC at {self.host}:{self.port}")
                    self.connected = True
                    await self._loop(client, dt, stop)
            except PlcError as exc:
                if self.connected:
                    self.log(f"PLC lost ({exc}); plant holds its inputs and retries")
                elif not waiting:
                    self.log(f"waiting for the PLC at {self.host}:{self.port} ({exc})")
                waiting = True
                self.connected = False
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(stop.wait(), RETRY_S)

    async def _loop(self, client: PlcClient, dt: float, stop: asyncio.Event) -> None:
        """Plant time follows the wall clock x speed: when the machine is busy and an exchange comes late,
        the plant integrates the missed steps (same inputs) instead of falling behind the PLC's clock,
        which keeps its own deadlines. At most `catch_up_s` of wall time is made up at once; a longer
        stall is skipped."""
        period = dt / self.speed
        t0 = time.perf_counter()
        done = 0  # plant steps since t0
        elapsed = 0.0  # plant time since the last measurement
        while not stop.is_set():
            writes = self.sim.measure(elapsed)
            await client.write_tags(writes)
            outputs = await client.read_tags(self.sim.read_names)
            due = int((time.perf_counter() - t0) / period) + 1
            n = max(1, due - done)
            if n > self.catch_up_s / period:  # a long stall: carry on from now
                t0, done, n = time.perf_counter() - period, 0, 1
            for _ in range(n):
                self.sim.apply(outputs, dt)
            done += n
            elapsed = n * dt
            self.steps += 1
            self.late_steps += n - 1
            delay = t0 + done * period - time.perf_counter()
            if delay > 0:
                await asyncio.sleep(delay)


def _parse_speed(speed: float) -> int:
    if not math.isfinite(speed) or speed < 1 or speed != int(speed):
        raise ValueError(f"--speed must be a whole number >= 1 (it divides the TASK interval), not {speed:g}")
    return int(speed)


class _Console:
    """Standard-input commands, read in a thread (works for a terminal and for a pipe)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, handle: Callable[[str], None]) -> None:
        import threading

        self.loop, self.handle = loop, handle
        threading.Thread(target=self._read, name="simulate-stdin", daemon=True).start()

    def _read(self) -> None:
        try:
            for line in sys.stdin:
                self.loop.call_soon_threadsafe(self.handle, line.strip())
        except (OSError, ValueError):
            return


async def simulate(sim: PlantSim, *, host: str, port: int, speed: int, plc: tuple[str, int] | None,
                   log: Callable[[str], None] = print) -> int:
    import signal

    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    soft = None
    if plc is None:
        from plc.bundle import bundle_text, with_speed
        from plc.runtime.server import LATE_SCANS_MADE_UP, SoftPlc

        soft = SoftPlc(with_speed(bundle_text(), speed), host=host, port=port, stepped=False)
        await soft.start()
        target = ("127.0.0.1" if host in ("0.0.0.0", "") else host, soft.port)
        interval_ms = soft.app.interval_ns / 1e6
        await asyncio.sleep(STARTUP_SCANS * interval_ms / 1e3)
        log(f"soft-PLC listening on {host}:{soft.port} (real time, interval {interval_ms:g} ms, "
            f"speed {speed}x); Modbus TCP, OpenPLC's map (thermost regmap)")
    else:
        target = plc
    scenario = sim.scenario
    # the embedded soft-PLC skips the scans of a stall longer than its interval (an overrun), so the plant
    # beside it in this process does the same: made-up plant steps it never scanned would show the PLC a
    # plant moving faster than its cycle allows (the heater monitor's rate and model checks trip on that)
    catch_up = CATCH_UP_S
    if soft is not None:
        catch_up = max((LATE_SCANS_MADE_UP + 1) * soft.app.interval_ns / 1e9, scenario.dt_s / speed)
    runner = Simulation(sim, target[0], target[1], float(speed), log, catch_up_s=catch_up)

    async def plc_power(on: bool) -> None:
        assert soft is not None
        if on and soft._server is None:
            soft.requested_port = soft.port or port
            await soft.start()
            log("soft-PLC serving again")
        elif not on and soft._server is not None:
            await soft.close()
            log("soft-PLC stopped (no scans, no Modbus) until `plc on`")

    def handle(line: str) -> None:
        words = line.split()
        if words[:1] == ["plc"] and len(words) == 2 and words[1] in ("on", "off"):
            if soft is None:
                log("error: plc on|off needs the embedded soft-PLC")
            else:
                loop.create_task(plc_power(words[1] == "on"))
            return
        answer = sim.command(line)
        if answer:
            log(answer)

    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    _Console(loop, handle)
    log(f"plant: scenario {scenario.name}, zones "
        + ", ".join(f"{z.plc_zone} ({z.name})" for z in sim.zones)
        + f", step {scenario.dt_s:g} s every {scenario.dt_s / speed * 1e3:g} ms wall; Ctrl-C stops; {HELP}")
    try:
        await runner.run(stop)
    finally:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
        if soft is not None:
            await soft.close()
    log(f"stopped after {sim.t:.1f} s plant time ({runner.steps} exchanges with the PLC, "
        f"{runner.late_steps} plant steps caught up without one)")
    return 0


def main_simulate(args) -> int:
    from plc.cli import UserError

    from .regmap import RegisterMapError, load_register_map
    from .runner import parse_host_port
    from .scenario import ScenarioError, load_scenario, resolve_scenario

    try:
        speed = _parse_speed(args.speed)
        plc = parse_host_port(args.plc) if args.plc else None
        if not 0 <= args.port < 65536:
            raise ValueError(f"--port must be 0..65535, not {args.port}")
        scenario = load_scenario(resolve_scenario(args.scenario or DEFAULT_SCENARIO))
        sim = PlantSim(scenario, load_register_map())
        if plc is None and 100 % speed and speed != 1:
            from plc.bundle import bundle_text, with_speed

            with_speed(bundle_text(), speed)  # raises a clear UserError
    except (ValueError, ScenarioError, RegisterMapError) as exc:
        raise UserError(str(exc)) from None

    def log(text: str) -> None:
        print(f"simulate: {text}", flush=True)

    import logging

    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # connection trouble is reported above

    try:
        return asyncio.run(simulate(sim, host=args.host, port=args.port, speed=speed, plc=plc, log=log))
    except OSError as exc:
        raise UserError(f"cannot serve Modbus on {args.host}:{args.port}: {exc}") from None
