"""Scenario files (TOML): plant, zones with sensors, per-zone phases (mode, setpoint programme,
disturbances), controller variants to compare. Validation is strict and happens before anything starts
(the pydantic models of scenario_schema.py; its JSON Schema is docs/scenario.schema.json): an unknown key,
a missing field or an impossible value raises ScenarioError naming the file, the key path and why.
The format is documented in docs/harness.md.
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .plants import PLANT_MODELS, Plant
from .scenario_schema import (  # noqa: F401 - the format's vocabulary, importable from here
    ADC_KINDS,
    DISTURBANCE_FIELDS,
    MODES,
    OUTPUT_PATHS,
    PV_PATHS,
    SENSOR_FAULTS,
    PhaseTable,
    ScenarioFile,
    SensorTable,
    ValidationError,
    error_line,
    first_error,
)
from .sensors import AdcFrontEnd, Sensor

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"
DEFAULT_SCENARIO = "seed003_hotend_fuzzy"

UNTIL_EVENTS = ("tuned",)
class ScenarioError(ValueError):
    """A scenario file is invalid: the message names the file, the key and why."""


@dataclass
class Disturbance:
    kind: str
    at_s: float
    value: float | str | None = None


@dataclass
class Phase:
    name: str
    mode: str | None = None
    setpoint_c: float | None = None
    ramp_c_per_min: float | None = None
    manual_pct: float | None = None
    fuzzy: bool | None = None
    duration_s: float | None = None
    end_at_s: float | None = None  # absolute scenario time (aligns zones after event-driven phases)
    until: str | None = None
    timeout_s: float | None = None
    disturbances: list[Disturbance] = field(default_factory=list)
    writes: dict[str, float | int | bool] = field(default_factory=dict)


@dataclass
class SensorSpec:
    lag_s: float = 0.0
    noise_sigma_c: float = 0.0
    offset_c: float = 0.0
    adc: AdcFrontEnd = field(default_factory=AdcFrontEnd)

    def build(self, seed: int) -> Sensor:
        return Sensor(
            lag_s=self.lag_s,
            noise_sigma_c=self.noise_sigma_c,
            adc=dataclasses.replace(self.adc),
            seed=seed,
            offset_c=self.offset_c,
        )


@dataclass
class Zone:
    name: str
    plc_zone: int
    channel: int
    sensor: SensorSpec
    phases: list[Phase]


@dataclass
class Variant:
    name: str
    fuzzy: bool | None = None
    writes: dict[str, float | int | bool] = field(default_factory=dict)


@dataclass
class Target:
    """A figure the report judges (scenario `[[target]]`): measured vs paper, pass/fail vs goal."""

    phase: str
    metric: str
    zone: str | None = None
    variant: str | None = None
    paper: float | None = None
    goal: float | None = None
    better: str = "lower"
    source: str = ""


@dataclass
class Scenario:
    path: Path
    name: str
    description: str
    reference: str
    seed: int
    dt_s: float
    scans_per_step: int
    pv_path: str
    output_path: str
    plant_model: str
    plant_params: dict[str, Any]
    zones: list[Zone]
    variants: list[Variant]
    targets: list[Target] = field(default_factory=list)

    def build_plant(self) -> Plant:
        return PLANT_MODELS[self.plant_model](**self.plant_params)

    @property
    def nominal_duration_s(self) -> float:
        """Longest zone programme, counting an `until` phase at its timeout."""
        ends = []
        for z in self.zones:
            t = 0.0
            for p in z.phases:
                t = max(t, p.end_at_s) if p.end_at_s is not None else t + (p.duration_s or p.timeout_s or 0.0)
            ends.append(t)
        return max(ends)


def _sensor(t: SensorTable) -> SensorSpec:
    adc = AdcFrontEnd(
        kind=t.adc,
        bits=t.bits,
        ohm_per_count=t.ohm_per_count,
        ohm_at_zero=t.ohm_at_zero,
        pullup_ohm=t.pullup_ohm,
        r25_ohm=t.r25_ohm,
        beta_k=t.beta_k,
        noise_lsb=t.adc_noise_lsb,
    )
    return SensorSpec(lag_s=t.lag_s, noise_sigma_c=t.noise_sigma_c, offset_c=t.offset_c, adc=adc)


def _phase(t: PhaseTable) -> Phase:
    return Phase(
        name=t.name,
        mode=t.mode,
        setpoint_c=t.setpoint_c,
        ramp_c_per_min=t.ramp_c_per_min,
        manual_pct=t.manual_pct,
        fuzzy=t.fuzzy,
        duration_s=t.duration_s,
        end_at_s=t.end_at_s,
        until=t.until,
        timeout_s=t.timeout_s,
        disturbances=[Disturbance(kind=d.kind, at_s=d.at_s, value=d.value()) for d in t.disturbance],
        writes=dict(t.write),
    )


def load_scenario(path: str | Path) -> Scenario:
    """Parse and validate a scenario file; raises ScenarioError (file, key, why) on any problem."""
    from plc.cli import UserError, read_text_file

    file = Path(path)
    try:
        data = tomllib.loads(read_text_file(str(file), "scenario file"))
    except UserError as exc:
        raise ScenarioError(str(exc)) from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{file}: not valid TOML: {exc}") from exc
    try:
        doc = ScenarioFile.model_validate(data)
    except ValidationError as exc:
        errors = exc.errors()
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise ScenarioError(f"{file}: {error_line(first_error(errors), data)}{more}") from None
    zones = [
        Zone(name=z.name, plc_zone=z.plc_zone, channel=z.channel, sensor=_sensor(z.sensor),
             phases=[_phase(p) for p in z.phase])
        for z in doc.zone
    ]
    variants = [Variant(name=v.name, fuzzy=v.fuzzy, writes=dict(v.write)) for v in doc.variant]
    variants = variants or [Variant(name="as written")]
    return Scenario(
        path=file,
        name=doc.name,
        description=doc.description,
        reference=doc.reference,
        seed=doc.seed,
        dt_s=doc.dt_s,
        scans_per_step=doc.plc.scans_per_step,
        pv_path=doc.plc.pv_path,
        output_path=doc.plc.output,
        plant_model=doc.plant.model,
        plant_params=doc.plant_params(),
        zones=zones,
        variants=variants,
        targets=[Target(**t.model_dump()) for t in doc.target],
    )


def shipped_scenarios() -> list[Path]:
    return sorted(SCENARIO_DIR.glob("*.toml"))


def resolve_scenario(name_or_path: str | None) -> Path:
    """A path, or the stem of a shipped scenario; None = the default scenario."""
    if name_or_path is None:
        return SCENARIO_DIR / f"{DEFAULT_SCENARIO}.toml"
    p = Path(name_or_path)
    if p.exists() or p.suffix == ".toml":
        return p
    shipped = SCENARIO_DIR / f"{name_or_path}.toml"
    if shipped.exists():
        return shipped
    names = ", ".join(s.stem for s in shipped_scenarios())
    raise ScenarioError(f"{name_or_path}: no such scenario file or shipped scenario (shipped: {names})")
