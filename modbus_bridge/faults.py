"""Fault injection with the plant in the loop, over Modbus: heater open / weak / stuck on, sensor detached or
falling off, frozen PV and a PV writer that stops (stale PV).

One run: the scenario's plant and sensor, the project's bundle on the stepped soft-PLC (or a PLC given as
HOST:PORT), the zone self-tunes (the scenario's first phase), holds the setpoint in ACTIVE for `settle_s`,
then the fault is injected at the plant/sensor side and the loop runs `after_s` more. Everything the PLC
sees comes over Modbus. The result holds the trace, the detection time (first alarm bit of the fault's
class after the fault), the time the output went to 0 and stayed there, and the peak true temperature.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from .alarms import alarm_bits
from .binding import ZoneBinding, resolve_zone
from .client import PlcClient
from .loop import raw_sensor_parameters
from .plants import PlantDisturbance
from .runner import HarnessSetup, parse_host_port
from .scenario import Scenario, load_scenario, resolve_scenario

ROOM_C = 25.0  # a detached sensor relaxes towards the room, not towards the plant's model ambient
DETACH_TAU_S = 2.0  # sensor pulled off the block: its reading relaxes with this time constant
FALL_OFF_TAU_S = 15.0  # sensor slowly losing contact
WEAK_FRACTION = 0.3  # a weak heater delivers this fraction of the commanded power
STUCK_ON_PCT = 100.0
RESET_SCANS = 2
HEARTBEAT_MODULO = 1 << 31

# fault -> names of the alarm bits that count as its detection (FB_CtrlAlarms.st header)
FAULT_ALARMS: dict[str, tuple[str, ...]] = {
    "heater_open": ("heater_open", "runaway", "heatup_watch"),
    "heater_weak": ("heater_open", "runaway", "heatup_watch"),
    "stuck_on": ("stuck_on", "abs_high"),
    "sensor_detached": ("sensor_detached", "sensor_open", "sensor_short"),
    "sensor_falling_off": ("sensor_detached", "sensor_open", "sensor_short"),
    "frozen_pv": ("pv_frozen",),
    "stale_pv": ("pv_stale",),
}
FAULTS = tuple(FAULT_ALARMS)
MISMATCH = "model_mismatch"  # not a fault: the plant's T and L change after tuning; every alarm bit counts


@dataclass(frozen=True)
class ProgrammeStep:
    """A step of the nominal programme that follows the injection: setpoint offset and load change."""

    after_s: float  # plant seconds after the injection
    setpoint_delta_c: float = 0.0  # setpoint = the tuning setpoint + this
    load_pct: float = 0.0  # extra heat loss added at this step, % of full power


# a nominal programme for the mismatch runs: hold, setpoint 20 degC down and back, load step
MISMATCH_PROGRAMME = (ProgrammeStep(150.0, -20.0), ProgrammeStep(400.0, 0.0), ProgrammeStep(600.0, 0.0, 8.0))
MISMATCH_AFTER_S = 800.0


@dataclass
class FaultRun:
    scenario: str
    fault: str
    dead_time_s: float
    t_fault: float = math.nan
    tuned: bool = False
    t: list[float] = field(default_factory=list)
    pv: list[float] = field(default_factory=list)
    true_c: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    alarm: list[int] = field(default_factory=list)
    state: list[int] = field(default_factory=list)

    def _arrays(self) -> tuple[np.ndarray, ...]:
        return (np.asarray(self.t), np.asarray(self.alarm, dtype=np.int64), np.asarray(self.y),
                np.asarray(self.true_c))

    @property
    def mask(self) -> int:
        if self.fault == MISMATCH:
            return (1 << 32) - 1
        bits = alarm_bits()
        return sum(1 << bits[name].bit for name in FAULT_ALARMS[self.fault] if name in bits)

    def detection_s(self) -> float | None:
        """Plant seconds from the fault to the first alarm bit of its class."""
        t, alarm, _, _ = self._arrays()
        idx = np.flatnonzero((t >= self.t_fault) & ((alarm & self.mask) != 0))
        return float(t[idx[0]] - self.t_fault) if idx.size else None

    def off_s(self) -> float | None:
        """Plant seconds from the fault until the output is 0 and stays 0 to the end of the run."""
        t, _, y, _ = self._arrays()
        after = t >= self.t_fault
        nonzero = np.flatnonzero(after & (y != 0.0))
        if nonzero.size == 0:
            return 0.0
        last = nonzero[-1]
        return float(t[last + 1] - self.t_fault) if last + 1 < t.size else None

    def peak_c(self) -> float:
        t, _, _, true_c = self._arrays()
        after = true_c[t >= self.t_fault]
        return float(after.max()) if after.size else math.nan

    def alarms_before_fault(self) -> int:
        t, alarm, _, _ = self._arrays()
        before = alarm[t < self.t_fault]
        return int(np.bitwise_or.reduce(before)) if before.size else 0


class _FaultedZone:
    """The plant and sensor of one zone with the fault applied at the plant/sensor boundary."""

    def __init__(self, sc: Scenario, fault: str, scale: tuple[float, float] = (1.0, 1.0)) -> None:
        self.sc = sc
        self.zone = sc.zones[0]
        self.fault = fault
        self.plant = sc.build_plant()
        self.pdist = PlantDisturbance.for_channels(self.plant.channels)
        self.sensor = self.zone.sensor.build(seed=sc.seed * 1000)
        self.active = False
        self.t_fault = math.nan
        self.reading_at_fault = math.nan
        self.frozen: tuple[float, int] | None = None
        self.scale = scale  # model mismatch: plant time constant and dead time times these
        self.u = [0.0] * self.plant.channels

    def true_c(self) -> float:
        return self.plant.temperatures()[self.zone.channel]

    def measure(self, t: float, dt: float) -> float:
        true = self.true_c()
        if self.active and self.fault in ("sensor_detached", "sensor_falling_off"):
            tau = DETACH_TAU_S if self.fault == "sensor_detached" else FALL_OFF_TAU_S
            true = ROOM_C + (self.reading_at_fault - ROOM_C) * math.exp(-(t - self.t_fault) / tau)
        if self.active and self.fault == "frozen_pv" and self.frozen is not None:
            self.sensor.last_counts = self.frozen[1]
            return self.frozen[0]
        pv = self.sensor.measure(true, dt)
        if self.fault == "frozen_pv" and self.active:
            self.frozen = (pv, self.sensor.last_counts)
        return pv

    def inject(self, t: float) -> None:
        self.active = True
        self.t_fault = t
        self.reading_at_fault = self.true_c()
        if self.fault == MISMATCH:
            t_scale, l_scale = self.scale
            self.plant.time_constant_scale = t_scale  # type: ignore[attr-defined]
            self.plant.set_dead_time(self.plant.dead_time_s * l_scale)  # type: ignore[attr-defined]

    def step(self, y: float, dt: float) -> None:
        u = y
        if self.active and self.fault == "heater_open":
            u = 0.0  # the actuator in use (heater, or the cooler of a cooled zone) delivers nothing
        elif self.active and self.fault == "heater_weak":
            u = y * WEAK_FRACTION
        elif self.active and self.fault == "stuck_on":
            u = STUCK_ON_PCT
        self.u[self.zone.channel] = u
        self.plant.step(self.u, self.sc.dt_s, self.pdist)


def _dead_time_s(sc: Scenario, plant) -> float:
    if "dead_time_s" in sc.plant_params:
        return float(sc.plant_params["dead_time_s"])
    delay = getattr(plant, "delay_s", None)
    return float(delay()) if callable(delay) else 0.0


async def _run_on(client: PlcClient, sc: Scenario, fault: str, setup: HarnessSetup, settle_s: float,
                  after_s: float, stepped: bool, on_step=None, scale: tuple[float, float] = (1.0, 1.0),
                  programme: tuple[ProgrammeStep, ...] = ()) -> FaultRun:
    fz = _FaultedZone(sc, fault, scale)
    pending = sorted(programme, key=lambda p: p.after_s)
    b: ZoneBinding = resolve_zone(setup.regmap, fz.zone.plc_zone)
    codes = setup.codes
    run = FaultRun(scenario=sc.name, fault=fault, dead_time_s=_dead_time_s(sc, fz.plant))
    tune = fz.zone.phases[0]
    await client.write_tags({b["mode"]: codes.modes["RESET"]})
    if stepped:
        await client.step(RESET_SCANS)
    writes: dict = {b["setpoint"]: tune.setpoint_c, **tune.writes}
    raw = sc.pv_path == "raw"
    for role in ("pv_select", "raw_from_modbus"):
        if b.has(role):
            writes[b[role]] = raw
    if raw:
        writes.update(raw_sensor_parameters(b, fz.zone.sensor.adc))
    fz.sensor.reset(fz.true_c())
    pv0 = fz.sensor.measure(fz.true_c(), 0.0)  # the PV is in place before the controller runs
    writes[b["pv_raw"] if raw else b["pv"]] = fz.sensor.last_counts if raw else pv0
    await client.write_tags(writes)
    if stepped:  # parameter registers become requests on the next scan: apply them before TUNE starts
        await client.step(RESET_SCANS)
    await client.write_tags({b["mode"]: codes.modes["TUNE"]})
    reads = [b["y"], b["alarm"], b["state"]]
    tuned_code, dt = codes.states.get("TUNED"), sc.dt_s
    tune_limit = tune.timeout_s or 3000.0
    t_settled: float | None = None
    seq = 0
    k = 0
    while True:
        t = k * dt
        if t_settled is None and (run.tuned or t >= tune_limit):
            break
        if t_settled is not None and fz.active and t >= run.t_fault + after_s:
            break
        if t_settled is not None and not fz.active and t >= t_settled + settle_s:
            fz.inject(t)
            run.t_fault = t
        pv = fz.measure(t, dt if k else 0.0)
        step_writes: dict = {}
        while fz.active and pending and t >= run.t_fault + pending[0].after_s:
            item = pending.pop(0)
            step_writes[b["setpoint"]] = tune.setpoint_c + item.setpoint_delta_c
            fz.pdist.zones[fz.zone.channel].load_pct += item.load_pct
        if not (fz.active and fault == "stale_pv"):
            seq = (seq + 1) % HEARTBEAT_MODULO
            step_writes[b["pv_raw"] if raw else b["pv"]] = fz.sensor.last_counts if raw else pv
            if b.has("pv_seq"):
                step_writes[b["pv_seq"]] = seq
        values = await client.exchange(step_writes, sc.scans_per_step, reads)
        y, state = float(values[b["y"]]), int(values[b["state"]])
        run.t.append(t)
        run.pv.append(pv)
        run.true_c.append(fz.true_c())
        run.y.append(y)
        run.alarm.append(int(values[b["alarm"]]))
        run.state.append(state)
        if t_settled is None and state == tuned_code:
            run.tuned = True
            await client.write_tags({b["mode"]: codes.modes["ACTIVE"]})
            t_settled = t
        if on_step is not None:
            on_step(t, run)
        fz.step(y, dt)
        k += 1
        if t_settled is None and run.tuned:
            t_settled = t
    return run


async def run_fault(name: str, fault: str, setup: HarnessSetup | None = None, *, plc: str | None = None,
                    settle_s: float | None = None, after_s: float = 60.0, on_step=None) -> FaultRun:
    """Tune, settle, inject `fault` on the first zone of scenario `name`; returns the trace and figures."""
    if fault not in FAULT_ALARMS:
        raise ValueError(f"unknown fault {fault!r}; known: {', '.join(FAULTS)}")
    setup = setup or HarnessSetup.default()
    sc = load_scenario(resolve_scenario(name))
    sc = dataclasses.replace(sc, zones=sc.zones[:1])
    if settle_s is None:
        settle_s = 120.0
    if plc is not None:
        host, port = parse_host_port(plc)
        async with PlcClient(host, port, setup.regmap, name="PLC") as client:
            return await _run_on(client, sc, fault, setup, settle_s, after_s, await client.stepped())
    from plc.runtime.server import SoftPlc

    async with SoftPlc(setup.program_text(), host="127.0.0.1", port=0, stepped=True) as soft:
        async with PlcClient("127.0.0.1", soft.port, setup.regmap, name="soft-PLC") as client:
            if on_step is not None:
                app = soft.app
                return await _run_on(client, sc, fault, setup, settle_s, after_s, True,
                                     lambda t, run: on_step(t, run, app))
            return await _run_on(client, sc, fault, setup, settle_s, after_s, True)


async def run_mismatch(name: str, time_constant_scale: float, dead_time_scale: float,
                       setup: HarnessSetup | None = None, *, plc: str | None = None,
                       programme: tuple[ProgrammeStep, ...] = MISMATCH_PROGRAMME,
                       after_s: float = MISMATCH_AFTER_S) -> FaultRun:
    """Tune on the nominal plant; the moment it is tuned the plant's T and L change by the given factors
    (the controller's identified model is then off by that much) and the nominal programme runs. A first-
    order-plus-dead-time plant (linear.Fopdt) is needed; detection_s() is the first alarm bit of any kind."""
    setup = setup or HarnessSetup.default()
    sc = load_scenario(resolve_scenario(name))
    sc = dataclasses.replace(sc, zones=sc.zones[:1])
    if not hasattr(sc.build_plant(), "set_dead_time"):
        raise ValueError(f"{name}: the plant cannot change its dead time (an FOPDT plant is needed)")
    scale = (time_constant_scale, dead_time_scale)
    if plc is not None:
        host, port = parse_host_port(plc)
        async with PlcClient(host, port, setup.regmap, name="PLC") as client:
            return await _run_on(client, sc, MISMATCH, setup, 0.0, after_s, await client.stepped(),
                                 scale=scale, programme=programme)
    from plc.runtime.server import SoftPlc

    async with SoftPlc(setup.program_text(), host="127.0.0.1", port=0, stepped=True) as soft:
        async with PlcClient("127.0.0.1", soft.port, setup.regmap, name="soft-PLC") as client:
            return await _run_on(client, sc, MISMATCH, setup, 0.0, after_s, True, scale=scale,
                                 programme=programme)


def open_loop_departure(name: str, fault: str, y0: float, after_s: float, rest_s: float = 40000.0) -> float:
    """Detection bound: how far the true temperature of scenario `name`'s plant departs, `after_s` after an
    actuator fault, from where it would be without it, open loop from rest at the output `y0` (%). A check
    on the PV cannot see less than this (compare with the sensor's count and noise)."""
    sc = load_scenario(resolve_scenario(name))
    if fault not in ("heater_open", "heater_weak", "stuck_on"):
        raise ValueError(f"{fault!r} is not an actuator fault")
    faulted = {"heater_open": 0.0, "heater_weak": y0 * WEAK_FRACTION, "stuck_on": STUCK_ON_PCT}[fault]
    plant = sc.build_plant()
    dist = PlantDisturbance.for_channels(plant.channels)
    channel = sc.zones[0].channel
    u = [0.0] * plant.channels
    u[channel] = y0
    for _ in range(round(rest_s / sc.dt_s)):
        plant.step(u, sc.dt_s, dist)
    other, other_dist = copy.deepcopy(plant), copy.deepcopy(dist)
    u_fault = list(u)
    u_fault[channel] = faulted
    for _ in range(round(after_s / sc.dt_s)):
        plant.step(u, sc.dt_s, dist)
        other.step(u_fault, sc.dt_s, other_dist)
    return other.temperatures()[channel] - plant.temperatures()[channel]
