"""The loop closer: plant <-> PLC over Modbus, one plant step at a time.

Each plant step (dt = scenario.dt_s of controller time): every zone's phase sequencer writes what its
programme asks (mode, setpoint or ramp point, fuzzy switch, manual value), the sensor measures the
plant and the process value goes to the PLC (REAL tag, or raw ADC counts), the PLC scans
(stepped: `scans_per_step` scans through the STEP register; real time: the PLC scans on its own
clock and the harness keeps wall-clock pace dt/speed, recording the jitter), the outputs are read
(analog output tag, or the PWM coils sampled every scan), and the plant integrates dt with them.
Stepped mode is deterministic: same scenario, same seed -> same trace, bit for bit.
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from . import kept_values
from .binding import RAW_FULL_SCALE, RAW_SENSOR_ROLES, UNLOCK_KEY, ControllerCodes, ZoneBinding
from .client import PlcClient, PlcError
from .plants import Plant, PlantDisturbance, ZoneDisturbance
from .preflight import check_bindings
from .regmap import RegisterMapError
from .scenario import Phase, Scenario, Variant, Zone
from .sensors import Sensor

PERCENT = 100.0
# the gains the PID runs with (the set in use, as the fuzzy adapter left it), traced through the run
EFFECTIVE_GAIN_ROLES = ("kp_eff", "tn_eff", "tv_eff")
# traced through the run: the effective gains and the tuned set and identified plant (kept_values.TUNED)
GAIN_ROLES = (*EFFECTIVE_GAIN_ROLES, *kept_values.roles(kept_values.TUNED, traced=True))
# read with the gains but kept only as tuning results (no trace)
TUNED_ONLY_ROLES = kept_values.roles(kept_values.TUNED, traced=False)
# read with the gains and kept per phase while a feature runs: group -> (the role that is non-zero while it
# runs, the roles kept): the fuzzy adapter's Ms bound while its coil is on, the plant as the model-based
# setpoint response measured it while a response runs
RUNNING_GROUPS: dict[str, tuple[str, tuple[str, ...]]] = {
    "adapter": (kept_values.ADAPTER_GATE, kept_values.roles(kept_values.ADAPTER)),
    "heatup": (kept_values.HEATUP_GATE, kept_values.roles(kept_values.HEATUP)),
}
TUNED_ROLES = kept_values.roles(kept_values.TUNED)
PROGRESS_EVERY = 50  # plant steps between progress reports
# plant steps between reads of gains, identified plant, state and error id (1 s at dt = 0.1 s); the state
# is read every step while a zone waits for an event (until = "tuned")
GAIN_READ_EVERY = 10
SECONDS_PER_MINUTE = 60.0


@dataclass
class PhaseRecord:
    zone: str
    name: str
    t_start: float
    t_end: float = math.nan
    mode: str | None = None
    fuzzy: bool | None = None
    setpoint_before: float = math.nan
    setpoint: float = math.nan
    ramp_c_per_min: float | None = None
    pv_start: float = math.nan
    disturbances: list[tuple[float, str, float | str | None]] = field(default_factory=list)
    outcome: str = "ok"
    tuned: dict[str, float] = field(default_factory=dict)
    # RUNNING_GROUPS: group -> {role: value} as last read while the feature ran
    running: dict[str, dict[str, float]] = field(default_factory=dict)


@dataclass
class ZoneTrace:
    name: str
    plc_zone: int
    t: list[float] = field(default_factory=list)
    pv: list[float] = field(default_factory=list)  # what the PLC was given (after sensor chain)
    true_c: list[float] = field(default_factory=list)  # plant temperature at the sensor
    setpoint: list[float] = field(default_factory=list)
    u: list[float] = field(default_factory=list)  # controller output applied to the plant, %
    y: list[float] = field(default_factory=list)  # the controller's analog output register, %
    pwm: list[int] = field(default_factory=list)
    state: list[int] = field(default_factory=list)
    alarm: list[int] = field(default_factory=list)
    phase: list[str] = field(default_factory=list)
    gains: dict[str, list[float]] = field(default_factory=dict)
    phases: list[PhaseRecord] = field(default_factory=list)


@dataclass
class RunResult:
    scenario: Scenario
    variant: Variant
    zones: list[ZoneTrace]
    steps: int = 0
    plant_time_s: float = 0.0
    wall_s: float = 0.0
    plant_cpu_s: float = 0.0
    realtime: bool = False
    jitter_ms: list[float] = field(default_factory=list)
    error: str | None = None
    interrupted: bool = False  # stopped by SIGINT/SIGTERM: the trace is what was measured until then
    plot_path: str | None = None  # set when the plot was already drawn (parallel variants draw their own)


class ZoneSequencer:
    """Runs one zone's phase programme; collects the register writes each step asks for."""

    def __init__(
        self,
        zone: Zone,
        binding: ZoneBinding,
        codes: ControllerCodes,
        variant: Variant,
        disturbance: ZoneDisturbance,
        plant_dist: PlantDisturbance,
        sensor: Sensor,
        trace: ZoneTrace,
    ):
        self.zone, self.binding, self.codes, self.variant = zone, binding, codes, variant
        self.dist, self.plant_dist, self.sensor, self.trace = disturbance, plant_dist, sensor, trace
        self.index = -1
        self.phase_start = 0.0
        self.setpoint = math.nan
        self.ramp_target: float | None = None
        self.ramp_rate_c_s = 0.0
        self.pending: list = []
        self.finished = False
        self.plant: Plant | None = None

    @property
    def phase(self) -> Phase:
        return self.zone.phases[self.index]

    def fuzzy_for(self, phase: Phase) -> bool | None:
        if phase.fuzzy is None:
            return None
        return self.variant.fuzzy if self.variant.fuzzy is not None else phase.fuzzy

    def _enter(self, t: float, pv: float, writes: dict) -> None:
        self.index += 1
        if self.index >= len(self.zone.phases):
            self.finished = True
            return
        ph = self.phase
        self.phase_start = t
        rec = PhaseRecord(
            zone=self.zone.name,
            name=ph.name,
            t_start=t,
            mode=ph.mode,
            fuzzy=self.fuzzy_for(ph),
            setpoint_before=self.setpoint,
            ramp_c_per_min=ph.ramp_c_per_min,
            pv_start=pv,
        )
        if self.index == 0:
            writes.update(self.variant.writes)
        writes.update(ph.writes)
        if ph.writes and self.binding.has("unlock"):
            # the scenario acts as the commissioning engineer: its writes may touch protected settings
            writes[self.binding["unlock"]] = UNLOCK_KEY
        if ph.mode is not None:
            writes[self.binding["mode"]] = self.codes.modes[ph.mode]
        fuzzy = self.fuzzy_for(ph)
        if fuzzy is not None:
            writes[self.binding["fuzzy"]] = bool(fuzzy)
        if ph.manual_pct is not None:
            writes[self.binding["manual"]] = ph.manual_pct
        if ph.setpoint_c is not None:
            if ph.ramp_c_per_min is not None and not math.isnan(self.setpoint):
                self.ramp_target = ph.setpoint_c
                self.ramp_rate_c_s = ph.ramp_c_per_min / SECONDS_PER_MINUTE
            else:
                self.ramp_target = None
                self.setpoint = ph.setpoint_c
                writes[self.binding["setpoint"]] = self.setpoint
        rec.setpoint = ph.setpoint_c if ph.setpoint_c is not None else self.setpoint
        self.pending = sorted(ph.disturbances, key=lambda d: d.at_s)
        self.trace.phases.append(rec)

    def start(self, t: float, pv: float, writes: dict) -> None:
        self._enter(t, pv, writes)

    def planned_end(self, t: float) -> float:
        """When this zone's programme should end, as planned now: a phase waiting for an event counts at
        its timeout; a finished zone ended when its last phase did."""
        if self.finished:
            return self.trace.phases[-1].t_end if self.trace.phases else t
        end = t
        for i, ph in enumerate(self.zone.phases[self.index :]):
            start = self.phase_start if i == 0 else end
            if ph.end_at_s is not None:
                end = max(start, ph.end_at_s)
            else:
                end = start + (ph.duration_s or ph.timeout_s or 0.0)
        return max(end, t)

    def update(
        self, t: float, dt: float, pv: float, state: int | None, writes: dict, error_id: int | None = None
    ) -> None:
        """Called once per plant step before the PLC scans: phase changes, ramps, disturbances."""
        if self.finished:
            return
        ph = self.phase
        rec = self.trace.phases[-1]
        elapsed = t - self.phase_start
        done = False
        if ph.until == "tuned" and state is not None:
            if state == self.codes.states.get("TUNED"):
                done = True
            elif state == self.codes.states.get("ERROR"):
                rec.outcome = "tuning error" if error_id is None else f"tuning error {error_id}"
                rec.t_end = t
                self.finished = True
                return
            elif ph.timeout_s is not None and elapsed >= ph.timeout_s:
                rec.outcome = "timeout"
                rec.t_end = t
                self.finished = True
                return
        elif ph.duration_s is not None and elapsed >= ph.duration_s - 1e-9:
            done = True
        elif ph.end_at_s is not None and t >= ph.end_at_s - 1e-9:
            done = True
        if done:
            rec.t_end = t
            self._enter(t, pv, writes)
            if self.finished:
                return
            elapsed = 0.0
        while self.pending and self.pending[0].at_s <= elapsed + 1e-9:
            d = self.pending.pop(0)
            self._apply(d.kind, d.value)
            self.trace.phases[-1].disturbances.append((t, d.kind, d.value))
        if self.ramp_target is not None:
            step = self.ramp_rate_c_s * dt
            gap = self.ramp_target - self.setpoint
            self.setpoint = self.ramp_target if abs(gap) <= step else self.setpoint + math.copysign(step, gap)
            if self.setpoint == self.ramp_target:
                self.ramp_target = None
            writes[self.binding["setpoint"]] = self.setpoint

    def _apply(self, kind: str, value: float | str | None) -> None:
        if kind == "load_step":
            self.dist.load_pct += float(value)  # type: ignore[arg-type]
        elif kind == "ambient_step":
            self.plant_dist.ambient_offset_c += float(value)  # type: ignore[arg-type]
        elif kind == "fan":
            self.dist.fan = float(value)  # type: ignore[arg-type]
        elif kind == "filament":
            self.dist.filament_mm_s = float(value)  # type: ignore[arg-type]
        elif kind == "heater_fail":
            self.dist.heater_failed = True
        elif kind == "sensor_fault":
            self.sensor.fault = str(value)
        elif kind == "model_mismatch" and self.plant is not None:
            self.plant.time_constant_scale = float(value)  # type: ignore[attr-defined, arg-type]
        elif kind == "dead_time_mismatch" and self.plant is not None:
            self.plant.set_dead_time(self.plant.dead_time_s * float(value))  # type: ignore[attr-defined, arg-type]


async def _pwm_step(
    client: PlcClient, writes: dict, scans: int, read_names: list[str], pwm_names: list[str]
) -> dict:
    """PWM outputs averaged over a plant step of several scans: the coils are sampled after every scan."""
    values = dict(await client.exchange(writes, 1, read_names))
    sums = {n: float(values[n]) for n in pwm_names}
    for _ in range(scans - 1):
        sample = await client.step_and_read(1, pwm_names)
        for n in pwm_names:
            sums[n] += float(sample[n])
    values.update({n: total / scans for n, total in sums.items()})
    return values


def raw_sensor_parameters(b: ZoneBinding, adc) -> dict[str, float]:
    """The application's raw conversion registers (when it has them) set to the simulated front end, so
    both ends agree: NTC R25, beta and pull-up; PT100 resistance at count 0 and at full scale."""
    values = {
        "ntc_r25": adc.r25_ohm,
        "ntc_beta": adc.beta_k,
        "ntc_pullup": adc.pullup_ohm,
        "pt100_res_low": adc.ohm_at_zero,
        "pt100_res_high": adc.ohm_at_zero + RAW_FULL_SCALE * adc.ohm_per_count,
    }
    return {b[role]: values[role] for role in RAW_SENSOR_ROLES.get(adc.kind, ()) if b.has(role)}


ProgressFn = Callable[[float, float], None]
StopFn = Callable[[], str | None]  # the reason to stop now (e.g. "interrupted by SIGINT"), else None


@dataclass
class _ReadPlan:
    """Which registers are read when: every step (outputs, alarm word), while a zone waits for an event
    or every GAIN_READ_EVERY steps (state, error id), every GAIN_READ_EVERY steps and on a state change
    (gains, identified plant)."""

    every_step: list[str]
    status: list[str]
    slow: list[str]
    pwm: list[str]

    @staticmethod
    def of(scenario: Scenario, bindings: dict[int, ZoneBinding], client: PlcClient) -> _ReadPlan:
        every, status, slow = [], [], []
        for z in scenario.zones:
            b = bindings[z.plc_zone]
            status += [b["state"]] + ([b["error"]] if b.has("error") else [])
            every += [b[r] for r in ("alarm", "y") if b.has(r)]
            if scenario.output_path == "pwm":
                every += [b["pwm_heat"]] + ([b["pwm_cool"]] if b.has("pwm_cool") else [])
            slow += [b[r] for r in (*GAIN_ROLES, *TUNED_ONLY_ROLES) if b.has(r)]
            for gate, roles in RUNNING_GROUPS.values():
                if b.has(gate) and b.has(roles[0]):
                    slow += [b[gate]] + [b[r] for r in roles if b.has(r)]
        return _ReadPlan(every, status, slow, [n for n in every if client.regmap[n].is_bit])


class _LoopCloser:
    """State of one run; `close_loop` is the entry point."""

    def __init__(
        self,
        scenario: Scenario,
        variant: Variant,
        client: PlcClient,
        bindings: dict[int, ZoneBinding],
        codes: ControllerCodes,
        realtime: bool,
        speed: float,
    ) -> None:
        self.scenario, self.client, self.realtime, self.speed = scenario, client, realtime, speed
        self.plant: Plant = scenario.build_plant()
        self.pdist = PlantDisturbance.for_channels(self.plant.channels)
        self.traces = [ZoneTrace(name=z.name, plc_zone=z.plc_zone) for z in scenario.zones]
        self.sensors = [z.sensor.build(seed=scenario.seed * 1000 + i) for i, z in enumerate(scenario.zones)]
        self.seqs = [
            ZoneSequencer(
                z, bindings[z.plc_zone], codes, variant, self.pdist.zones[z.channel], self.pdist, s, tr
            )
            for z, s, tr in zip(scenario.zones, self.sensors, self.traces, strict=True)
        ]
        for seq in self.seqs:
            seq.plant = self.plant
        self.plan = _ReadPlan.of(scenario, bindings, client)
        self.result = RunResult(scenario=scenario, variant=variant, zones=self.traces, realtime=realtime)
        self.u = [0.0] * self.plant.channels
        self.states: list[int | None] = [None] * len(self.seqs)
        self.error_ids: list[int | None] = [None] * len(self.seqs)
        self.slow_values: dict = {}
        self.wall0 = time.perf_counter()

    async def start(self) -> None:
        """Sensors at the plant's initial temperature, PV source selection, first phase of every zone."""
        writes: dict = {}
        temps = self.plant.temperatures()
        for z, s, seq in zip(self.scenario.zones, self.sensors, self.seqs, strict=True):
            s.reset(temps[z.channel])
            raw = self.scenario.pv_path == "raw"
            for role in ("pv_select", "raw_from_modbus"):
                if seq.binding.has(role):
                    writes[seq.binding[role]] = raw
            if raw:
                writes.update(raw_sensor_parameters(seq.binding, z.sensor.adc))
            seq.start(0.0, temps[z.channel], writes)
        await self.write_mode_last(writes)

    async def write_mode_last(self, writes: dict) -> None:
        """Setpoints and parameters before the mode: a PLC scanning on its own clock between two requests
        must never see the new mode with the old setpoint (TUNE would start against the wrong W)."""
        modes = {seq.binding["mode"] for seq in self.seqs}
        first = {n: v for n, v in writes.items() if n not in modes}
        last = {n: v for n, v in writes.items() if n in modes}
        for part in (first, last):
            if part:
                await self.client.write_tags(part)

    def sequence_and_measure(self, k: int, t: float, temps: list[float]) -> tuple[dict, list[float]]:
        """Phase programmes advance, sensors measure; returns the writes of this step and the PVs."""
        writes: dict = {}
        measured = []
        dt = self.scenario.dt_s
        for i, (z, s, seq) in enumerate(zip(self.scenario.zones, self.sensors, self.seqs, strict=True)):
            pv = s.measure(temps[z.channel], dt if k else 0.0)
            measured.append(pv)
            seq.update(t, dt, pv, self.states[i], writes, self.error_ids[i])
            if self.scenario.pv_path == "raw":
                writes[seq.binding["pv_raw"]] = s.last_counts
            else:
                writes[seq.binding["pv"]] = pv
            if seq.binding.has("pv_seq"):  # heartbeat with every new PV (stale-PV watchdog)
                writes[seq.binding["pv_seq"]] = k + 1
        return writes, measured

    async def exchange(self, k: int, t: float, writes: dict) -> tuple[dict, list[int]]:
        """Inputs to the PLC, scans (stepped) or pacing (real time), outputs back; the state when due."""
        sc, client, plan = self.scenario, self.client, self.plan
        if self.realtime:
            return await self._exchange_realtime(k, t, writes)
        if sc.output_path == "pwm" and sc.scans_per_step > 1:
            values = await _pwm_step(client, writes, sc.scans_per_step, plan.every_step, plan.pwm)
        else:
            values = await client.exchange(writes, sc.scans_per_step, plan.every_step)
        waiting = any(not seq.finished and seq.phase.until is not None for seq in self.seqs)
        if waiting or k % GAIN_READ_EVERY == 0:
            values.update(await client.read_tags(plan.status))
            new_states = [int(values[seq.binding["state"]]) for seq in self.seqs]
            self.error_ids = [
                int(values[q.binding["error"]]) if q.binding.has("error") else None for q in self.seqs
            ]
        else:
            new_states = list(self.states)  # type: ignore[arg-type]
        if plan.slow and (k % GAIN_READ_EVERY == 0 or new_states != self.states):
            self.slow_values = await client.read_tags(plan.slow)
        return values, new_states

    async def _exchange_realtime(self, k: int, t: float, writes: dict) -> tuple[dict, list[int]]:
        """Real time: the inputs of time t go out at once, the outputs are read at t + dt, when the PLC has
        scanned them, and drive the plant over [t, t + dt] - the order of the stepped loop, so the harness
        adds no dead time of its own (reading right after writing returned the output of the previous
        sample: one plant step of extra delay). Slow reads happen while the step waits."""
        client, plan = self.client, self.plan
        await self.write_mode_last(writes)
        if plan.slow and k % GAIN_READ_EVERY == 0:
            self.slow_values = await client.read_tags(plan.slow)
        target = self.wall0 + (t + self.scenario.dt_s) / self.speed
        delay = target - time.perf_counter()
        if delay > 0:
            await asyncio.sleep(delay)
        self.result.jitter_ms.append((time.perf_counter() - target) * 1e3)
        values = dict(await client.read_tags(plan.every_step + plan.status))
        new_states = [int(values[seq.binding["state"]]) for seq in self.seqs]
        self.error_ids = [
            int(values[q.binding["error"]]) if q.binding.has("error") else None for q in self.seqs
        ]
        if plan.slow and new_states != self.states:
            self.slow_values = await client.read_tags(plan.slow)
        return values, new_states

    def record(
        self, t: float, temps: list[float], measured: list[float], values: dict, states: list[int]
    ) -> None:
        """Outputs to the plant inputs, one trace row per zone, tuned parameters into the phase record."""
        for i, (z, seq, tr) in enumerate(zip(self.scenario.zones, self.seqs, self.traces, strict=True)):
            b = seq.binding
            self.states[i] = states[i]
            if self.scenario.output_path == "pwm":
                heat = float(values[b["pwm_heat"]])  # duty over the step (1 sample per scan)
                cool = float(values[b["pwm_cool"]]) if b.has("pwm_cool") else 0.0
                self.u[z.channel] = PERCENT * (heat - cool)
                tr.pwm.append(round(heat) - round(cool))
            else:
                self.u[z.channel] = float(values[b["y"]])
            if b.has("y"):
                tr.y.append(float(values[b["y"]]))
            if b.has("alarm"):
                tr.alarm.append(int(values[b["alarm"]]))
            tr.t.append(t)
            tr.pv.append(measured[i])
            tr.true_c.append(temps[z.channel])
            tr.setpoint.append(seq.setpoint)
            tr.u.append(self.u[z.channel])
            tr.state.append(states[i])
            tr.phase.append(seq.phase.name if not seq.finished else "")
            for role in GAIN_ROLES:
                if b.has(role):
                    tr.gains.setdefault(role, []).append(float(self.slow_values[b[role]]))
            if tr.phases and not seq.finished:
                for role in TUNED_ROLES:
                    if b.has(role):
                        tr.phases[-1].tuned[role] = float(self.slow_values[b[role]])
                for group, (gate, roles) in RUNNING_GROUPS.items():
                    if b.has(gate) and b.has(roles[0]) and self.slow_values[b[gate]]:
                        tr.phases[-1].running[group] = {
                            r: float(self.slow_values[b[r]]) for r in roles if b.has(r)
                        }

    def planned_total(self, t: float, horizon: float) -> float:
        """The plant time the run needs as planned at time t (the progress total)."""
        return min(horizon, max(seq.planned_end(t) for seq in self.seqs))

    def finish(self, k: int) -> None:
        end_t = k * self.scenario.dt_s
        for tr in self.traces:
            for rec in tr.phases:
                if math.isnan(rec.t_end):
                    rec.t_end = end_t
                    if self.result.error and rec is tr.phases[-1]:
                        rec.outcome = "aborted"
        self.result.steps = k
        self.result.plant_time_s = end_t
        self.result.wall_s = time.perf_counter() - self.wall0


async def close_loop(
    scenario: Scenario,
    variant: Variant,
    client: PlcClient,
    bindings: dict[int, ZoneBinding],
    codes: ControllerCodes,
    *,
    realtime: bool = False,
    speed: float = 1.0,
    progress: ProgressFn | None = None,
    max_plant_time_s: float | None = None,
    should_stop: StopFn | None = None,
) -> RunResult:
    """Run the scenario against one PLC. PLC errors end the run with `error` set; the trace so far is kept.
    `should_stop` is asked every step; a reason ends the run the same way, `interrupted` set (so does a
    cancellation of the task)."""
    check_bindings(scenario, bindings, codes, client.regmap, stepped=not realtime)
    run = _LoopCloser(scenario, variant, client, bindings, codes, realtime, speed)
    horizon = max_plant_time_s or scenario.nominal_duration_s
    dt = scenario.dt_s
    k = 0
    try:
        await run.start()
        while not all(seq.finished for seq in run.seqs):
            t = k * dt
            if t >= horizon - 1e-9:
                break
            temps = run.plant.temperatures()
            writes, measured = run.sequence_and_measure(k, t, temps)
            if all(seq.finished for seq in run.seqs):
                break
            if should_stop is not None and (reason := should_stop()):
                run.result.error, run.result.interrupted = reason, True
                break
            values, states = await run.exchange(k, t, writes)
            run.record(t, temps, measured, values, states)
            c0 = time.perf_counter()
            run.plant.step(run.u, dt, run.pdist)
            run.result.plant_cpu_s += time.perf_counter() - c0
            k += 1
            if progress is not None and k % PROGRESS_EVERY == 0:
                progress(t + dt, run.planned_total(t + dt, horizon))
    except (PlcError, RegisterMapError) as exc:
        run.result.error = str(exc)
    except asyncio.CancelledError:  # interrupted while waiting for the PLC: keep what was measured
        run.result.error, run.result.interrupted = "interrupted", True
    finally:
        run.finish(k)
        if progress is not None:
            done = min(run.result.plant_time_s, horizon)
            # a run that went to its end is 100 %; an aborted one shows how far it got of the plan
            progress(done, done if run.result.error is None else run.planned_total(done, horizon))
    return run.result
