"""Scenario files (TOML): plant, zones with sensors, per-zone phases (mode, setpoint programme,
disturbances), controller variants to compare. Validation is strict and happens before anything starts:
an unknown key, a missing field or an impossible value raises ScenarioError naming the file, the key
path and why. The format is documented in docs/harness.md.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .plants import PLANT_MODELS, Plant, array_fields
from .sensors import AdcFrontEnd, Sensor

SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"
DEFAULT_SCENARIO = "seed003_hotend_fuzzy"

MODES = ("IDLE", "PASSIVE", "ACTIVE", "RESET", "MANUAL", "TUNE")
UNTIL_EVENTS = ("tuned",)
PV_PATHS = ("real", "raw")
OUTPUT_PATHS = ("analog", "pwm")
ADC_KINDS = ("none", "pt100", "ntc")
MAX_ADC_BITS = 24
MIN_ADC_BITS = 8
DISTURBANCE_FIELDS: dict[str, dict[str, type]] = {
    "load_step": {"delta_pct": float},
    "ambient_step": {"delta_c": float},
    "fan": {"duty": float},
    "filament": {"speed_mm_s": float},
    "heater_fail": {},
    "sensor_fault": {"fault": str},
    "model_mismatch": {"time_constant_scale": float},
}
SENSOR_FAULTS = ("open", "short", "none")


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


class _Table:
    """Reads one TOML table, records which keys were used, refuses the rest."""

    def __init__(self, file: Path, path: str, data: Any) -> None:
        self.file, self.path = file, path
        if not isinstance(data, dict):
            self.fail("", "must be a table")
        self.data: dict[str, Any] = data
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def fail(self, name: str, why: str) -> None:
        key = self.key(name) if name else (self.path or "<top level>")
        raise ScenarioError(f"{self.file}: {key}: {why}")

    def get(
        self,
        name: str,
        kind: type,
        default: Any = ...,
        *,
        minimum: float | None = None,
        above: float | None = None,
        maximum: float | None = None,
        choices: tuple | None = None,
    ) -> Any:
        self.used.add(name)
        if name not in self.data:
            if default is ...:
                typo = difflib.get_close_matches(name, [k for k in self.data if k not in self.used], n=1)
                if typo:
                    self.fail(typo[0], f"unknown key (did you mean '{name}'?)")
                self.fail(name, "missing required field")
            return default
        value = self.data[name]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if kind in (int, float) and isinstance(value, bool) or not isinstance(value, kind):
            self.fail(name, f"must be {kind.__name__}, got {type(value).__name__} {value!r}")
        if kind is float and not math.isfinite(value):
            self.fail(name, f"must be a finite number, got {value!r}")
        if minimum is not None and value < minimum:
            self.fail(name, f"must be >= {minimum}, got {value!r}")
        if above is not None and value <= above:
            self.fail(name, f"must be > {above}, got {value!r}")
        if maximum is not None and value > maximum:
            self.fail(name, f"must be <= {maximum}, got {value!r}")
        if choices is not None and value not in choices:
            self.fail(name, f"must be one of {', '.join(map(str, choices))}, got {value!r}")
        return value

    def sub(self, name: str, required: bool = False) -> _Table:
        self.used.add(name)
        if name not in self.data:
            if required:
                self.fail(name, "missing required table")
            return _Table(self.file, self.key(name), {})
        return _Table(self.file, self.key(name), self.data[name])

    def array(self, name: str, required: bool = False) -> list[_Table]:
        self.used.add(name)
        items = self.data.get(name)
        if items is None:
            if required:
                self.fail(name, "missing required array of tables ([[" + self.key(name) + "]])")
            return []
        if not isinstance(items, list) or not items:
            self.fail(name, "must be a non-empty array of tables")
        return [_Table(self.file, f"{self.key(name)}[{i + 1}]", item) for i, item in enumerate(items)]

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            self.fail(unknown[0], "unknown key")


# plant fields that divide something: zero would be a plant without inertia or an infinite rate
POSITIVE_PLANT_FIELDS = (
    "time_constant_s",
    "time_constant2_s",
    "time_constant_scale",
    "gain_scale",
    "max_substep_s",
    "heater_divisor",
    "sensor_response_per_s",
    "max_rise_c",
    "loss_exponent",
)


def _must_be_positive(key: str) -> bool:
    return (
        key in POSITIVE_PLANT_FIELDS
        or "heat_capacity" in key
        or (key.endswith("_time_s") and key != "dead_time_s")
    )


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _plant_params(tab: _Table) -> tuple[str, dict[str, Any], Plant]:
    model = tab.get("model", str, choices=tuple(PLANT_MODELS))
    cls = PLANT_MODELS[model]
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    params: dict[str, Any] = {}
    for key, value in tab.data.items():
        if key == "model":
            continue
        if key not in fields:
            tab.fail(key, f"unknown key for plant model '{model}' (known: {', '.join(sorted(fields))})")
        if key in array_fields(model):
            if not isinstance(value, list) or not value or not all(_is_number(v) for v in value):
                tab.fail(key, f"must be a non-empty list of finite numbers, got {value!r}")
            params[key] = tuple(float(v) for v in value)
            tab.used.add(key)
            continue
        if isinstance(value, bool) or not isinstance(value, int | float):
            tab.fail(key, f"must be a number, got {value!r}")
        if not math.isfinite(float(value)):
            tab.fail(key, f"must be a finite number, got {value!r}")
        if key.endswith(("_s", "_scale", "_j_k", "_w", "_w_k")) and key != "initial_c" and float(value) < 0.0:
            tab.fail(key, f"must be >= 0, got {value!r}")
        if _must_be_positive(key) and float(value) <= 0.0:
            tab.fail(key, f"must be > 0, got {value!r}")
        params[key] = float(value)
        tab.used.add(key)
    missing = [
        n
        for n, f in fields.items()
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING and n not in params
    ]
    if missing:
        tab.fail(missing[0], f"missing required field for plant model '{model}'")
    try:
        plant = cls(**params)
    except (ValueError, ZeroDivisionError) as exc:
        tab.fail("", f"impossible plant parameters: {exc}")
    tab.done()
    return model, params, plant


def _sensor(tab: _Table) -> SensorSpec:
    adc_kind = tab.get("adc", str, "none", choices=ADC_KINDS)
    adc = AdcFrontEnd(
        kind=adc_kind,
        bits=tab.get("bits", int, 16, minimum=MIN_ADC_BITS, maximum=MAX_ADC_BITS),
        ohm_per_count=tab.get("ohm_per_count", float, 1.0 / 16.0, above=0.0),
        ohm_at_zero=tab.get("ohm_at_zero", float, 0.0, minimum=0.0),
        pullup_ohm=tab.get("pullup_ohm", float, 4700.0, above=0.0),
        r25_ohm=tab.get("r25_ohm", float, 100_000.0, above=0.0),
        beta_k=tab.get("beta_k", float, 3950.0, above=0.0),
    )
    spec = SensorSpec(
        lag_s=tab.get("lag_s", float, 0.0, minimum=0.0),
        noise_sigma_c=tab.get("noise_sigma_c", float, 0.0, minimum=0.0),
        offset_c=tab.get("offset_c", float, 0.0),
        adc=adc,
    )
    tab.done()
    return spec


def _disturbance(tab: _Table, phase_duration: float | None) -> Disturbance:
    kind = tab.get("kind", str, choices=tuple(DISTURBANCE_FIELDS))
    at_s = tab.get("at_s", float, 0.0, minimum=0.0)
    if phase_duration is not None and at_s > phase_duration:
        tab.fail("at_s", f"{at_s} s is after the end of its phase ({phase_duration} s)")
    value: float | str | None = None
    for name, kind_type in DISTURBANCE_FIELDS[kind].items():
        if kind_type is str:
            value = tab.get(name, str, choices=SENSOR_FAULTS)
        elif name == "duty":
            value = tab.get(name, float, minimum=0.0, maximum=1.0)
        elif name == "speed_mm_s":
            value = tab.get(name, float, minimum=0.0)
        elif name == "time_constant_scale":
            value = tab.get(name, float, above=0.0)
        else:
            value = tab.get(name, float)
    tab.done()
    return Disturbance(kind=kind, at_s=at_s, value=value)


def _phase(tab: _Table) -> Phase:
    ph = Phase(
        name=tab.get("name", str),
        mode=tab.get("mode", str, None, choices=MODES),
        setpoint_c=tab.get("setpoint_c", float, None),
        ramp_c_per_min=tab.get("ramp_c_per_min", float, None, above=0.0),
        manual_pct=tab.get("manual_pct", float, None, minimum=-100.0, maximum=100.0),
        fuzzy=tab.get("fuzzy", bool, None),
        duration_s=tab.get("duration_s", float, None, above=0.0),
        end_at_s=tab.get("end_at_s", float, None, above=0.0),
        until=tab.get("until", str, None, choices=UNTIL_EVENTS),
        timeout_s=tab.get("timeout_s", float, None, above=0.0),
    )
    if sum(x is not None for x in (ph.duration_s, ph.until, ph.end_at_s)) != 1:
        tab.fail("duration_s", "give exactly one of duration_s, until or end_at_s")
    if ph.until is not None and ph.timeout_s is None:
        tab.fail("timeout_s", "missing required field (a phase that waits for an event needs a timeout)")
    if ph.until is None and ph.timeout_s is not None:
        tab.fail("timeout_s", "only allowed together with until")
    if ph.until == "tuned" and ph.mode not in (None, "TUNE"):
        tab.fail("until", f"waiting for 'tuned' needs mode TUNE, got {ph.mode}")
    if ph.ramp_c_per_min is not None and ph.setpoint_c is None:
        tab.fail("ramp_c_per_min", "a ramp needs setpoint_c (the ramp's target)")
    ph.disturbances = [_disturbance(d, ph.duration_s) for d in tab.array("disturbance")]
    wtab = tab.sub("write")
    for tag, value in wtab.data.items():
        if not isinstance(value, bool | int | float) or (
            isinstance(value, float) and not math.isfinite(value)
        ):
            wtab.fail(tag, f"must be a finite number or a boolean, got {value!r}")
        ph.writes[tag] = value
        wtab.used.add(tag)
    tab.done()
    return ph


def load_scenario(path: str | Path) -> Scenario:
    """Parse and validate a scenario file; raises ScenarioError (file, key, why) on any problem."""
    file = Path(path)
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError as exc:
        raise ScenarioError(f"{file}: no such scenario file") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{file}: not valid TOML: {exc}") from exc
    top = _Table(file, "", data)
    name = top.get("name", str)
    description = top.get("description", str)
    reference = top.get("reference", str, "")
    seed = top.get("seed", int, 0, minimum=0)
    dt_s = top.get("dt_s", float, 0.1, above=0.0)
    plc = top.sub("plc")
    scans = plc.get("scans_per_step", int, 1, minimum=1)
    pv_path = plc.get("pv_path", str, "real", choices=PV_PATHS)
    output_path = plc.get("output", str, "analog", choices=OUTPUT_PATHS)
    plc.done()
    model, params, plant = _plant_params(top.sub("plant", required=True))
    zones = []
    seen: set[int] = set()
    for ztab in top.array("zone", required=True):
        channel = ztab.get("channel", int, 0, minimum=0)
        if channel >= plant.channels:
            ztab.fail("channel", f"plant '{model}' has {plant.channels} channel(s), got {channel}")
        plc_zone = ztab.get("plc_zone", int, minimum=1)
        if plc_zone in seen:
            ztab.fail("plc_zone", f"PLC zone {plc_zone} is used twice")
        seen.add(plc_zone)
        zname = ztab.get("name", str)
        sensor = _sensor(ztab.sub("sensor"))
        if pv_path == "raw" and sensor.adc.kind == "none":
            ztab.fail("sensor.adc", "plc.pv_path = 'raw' needs an ADC front end (pt100 or ntc)")
        phases = [_phase(p) for p in ztab.array("phase", required=True)]
        ztab.done()
        zones.append(Zone(name=zname, plc_zone=plc_zone, channel=channel, sensor=sensor, phases=phases))
    variants = []
    for vtab in top.array("variant"):
        variants.append(Variant(name=vtab.get("name", str), fuzzy=vtab.get("fuzzy", bool, None)))
        vtab.done()
    if not variants:
        variants = [Variant(name="as written")]
    top.done()
    return Scenario(
        path=file,
        name=name,
        description=description,
        reference=reference,
        seed=seed,
        dt_s=dt_s,
        scans_per_step=scans,
        pv_path=pv_path,
        output_path=output_path,
        plant_model=model,
        plant_params=params,
        zones=zones,
        variants=variants,
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
