"""The scenario file format as pydantic models: validation of a parsed TOML document and its JSON Schema.

`ScenarioFile.model_validate(data)` checks everything that can be checked without the PLC: types (strict:
no string for a number, no bool for a number), finite numbers, ranges, unknown keys, and the rules between
fields (one of duration_s/until/end_at_s, a timeout with until, a disturbance inside its phase, a channel
the plant has...). The plant table is a union discriminated on `model`, with one model per entry of
`plants.PLANT_MODELS`, derived from the plant dataclass (float fields; `*_s`, `*_scale`, `*_w`... >= 0;
time constants, heat capacities, scales > 0): a new plant kind registered there is in the schema at once;
a plant class may also bring its own pydantic model as `scenario_model`. `error_line()` turns a pydantic
error into `<key path>: <why>`, e.g. `zone[1].phase[3].disturbance[1].at_s: 50.0 s is after ...`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import typing
from typing import Annotated, Any, Literal, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StrictBool,
    StrictInt,
    StrictStr,
    create_model,
    model_validator,
)
from pydantic import ValidationError as ValidationError  # re-exported for scenario.py
from pydantic_core import PydanticCustomError

from .plants import PLANT_MODELS
from .sensors import DEFAULT_ADC_NOISE_LSB

MODES = ("IDLE", "PASSIVE", "ACTIVE", "RESET", "MANUAL", "TUNE")
PV_PATHS = ("real", "raw")
OUTPUT_PATHS = ("analog", "pwm")
ADC_KINDS = ("none", "pt100", "ntc")
SENSOR_FAULTS = ("open", "short", "none")
MAX_ADC_BITS = 24
MIN_ADC_BITS = 8
MAX_MANUAL_PCT = 100.0

Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
# >= 0 checked first: a negative time says ">= 0" as it did before, zero says "> 0"
Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0), Field(gt=0.0)]
NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0)]
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
NON_NEGATIVE_SUFFIXES = ("_s", "_scale", "_j_k", "_w", "_w_k")


class FieldProblem(ValueError):
    """A rule between fields, reported at `key` (relative to the model that found it)."""

    def __init__(self, key: str, why: str) -> None:
        super().__init__(why)
        self.key, self.why = key, why


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, populate_by_name=True)


# ---- plants -------------------------------------------------------------------------------------
def _number_list(value: Any) -> list[float]:
    ok = isinstance(value, list) and value and all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
    )
    if not ok:
        raise PydanticCustomError(
            "number_list", "must be a non-empty list of finite numbers, got {value}", {"value": repr(value)}
        )
    return [float(v) for v in value]


NumberList = Annotated[list[float], BeforeValidator(_number_list)]


def _plant_field(name: str, annotation: Any) -> Any:
    if name in POSITIVE_PLANT_FIELDS or "heat_capacity" in name or (
        name.endswith("_time_s") and name != "dead_time_s"
    ):
        return Positive
    if name.endswith(NON_NEGATIVE_SUFFIXES) and name != "initial_c":
        return NonNegative
    origin = typing.get_origin(annotation)
    if origin in (list, tuple):
        return NumberList
    return Finite


def plant_model_for(kind: str, cls: type) -> type[BaseModel]:
    custom = getattr(cls, "scenario_model", None)
    if isinstance(custom, type) and issubclass(custom, BaseModel):
        return custom
    hints = typing.get_type_hints(cls)
    fields: dict[str, Any] = {"model": (Literal[kind], ...)}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        kind_type = _plant_field(f.name, hints.get(f.name, float))
        fields[f.name] = (kind_type, ...) if required else (kind_type | None, None)
    doc = (cls.__doc__ or kind).strip().splitlines()[0]
    return create_model(f"Plant_{kind}", __base__=_Strict, __doc__=doc, **fields)


PLANT_SCHEMAS: dict[str, type[BaseModel]] = {k: plant_model_for(k, c) for k, c in PLANT_MODELS.items()}
PlantTable = Annotated[Union[tuple(PLANT_SCHEMAS.values())], Field(discriminator="model")]  # noqa: UP007


# ---- disturbances -------------------------------------------------------------------------------
class _Disturbance(_Strict):
    at_s: NonNegative = 0.0

    def value(self) -> float | str | None:
        return None


def _disturbance(kind: str, field: str | None = None, annotation: Any = None, doc: str = "") -> type:
    fields: dict[str, Any] = {"kind": (Literal[kind], ...)}
    if field is not None:
        fields[field] = (annotation, ...)
    model = create_model(f"Disturbance_{kind}", __base__=_Disturbance, __doc__=doc, **fields)
    if field is not None:
        model.value = lambda self: getattr(self, field)  # type: ignore[method-assign]
    return model


DISTURBANCE_MODELS = (
    _disturbance("load_step", "delta_pct", Finite, "load in % of heater power at the plant input (+ = loss)"),
    _disturbance("ambient_step", "delta_c", Finite, "ambient temperature change, degC"),
    _disturbance("fan", "duty", Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0, le=1.0)],
                 "part-cooling fan duty 0..1"),
    _disturbance("filament", "speed_mm_s", NonNegative, "filament feed, mm/s"),
    _disturbance("heater_fail", doc="the heater cartridge fails open"),
    _disturbance("sensor_fault", "fault", Literal[SENSOR_FAULTS], "sensor open / short / healed"),
    _disturbance("model_mismatch", "time_constant_scale", Positive, "plant time constants times this"),
    _disturbance("dead_time_mismatch", "dead_time_scale", Positive, "plant dead time times this"),
)
DISTURBANCE_FIELDS: dict[str, tuple[str, ...]] = {
    typing.get_args(m.model_fields["kind"].annotation)[0]: tuple(
        n for n in m.model_fields if n not in ("kind", "at_s")
    )
    for m in DISTURBANCE_MODELS
}
DisturbanceTable = Annotated[Union[DISTURBANCE_MODELS], Field(discriminator="kind")]  # noqa: UP007


# ---- phases, zones, the file --------------------------------------------------------------------
class PhaseTable(_Strict):
    name: StrictStr
    mode: Literal[MODES] | None = None
    setpoint_c: Finite | None = None
    ramp_c_per_min: Positive | None = None
    manual_pct: Annotated[float, Field(strict=True, allow_inf_nan=False, ge=-MAX_MANUAL_PCT,
                                       le=MAX_MANUAL_PCT)] | None = None
    fuzzy: StrictBool | None = None
    duration_s: Positive | None = None
    end_at_s: Positive | None = Field(None, description="absolute scenario time (aligns zones)")
    until: Literal["tuned"] | None = None
    timeout_s: Positive | None = None
    disturbance: list[DisturbanceTable] = Field(default_factory=list)
    write: dict[str, StrictBool | StrictInt | Finite] = Field(
        default_factory=dict, description="any writable tag of the register map"
    )

    @model_validator(mode="after")
    def _rules(self) -> PhaseTable:
        if sum(x is not None for x in (self.duration_s, self.until, self.end_at_s)) != 1:
            raise FieldProblem("duration_s", "give exactly one of duration_s, until or end_at_s")
        if self.until is not None and self.timeout_s is None:
            raise FieldProblem("timeout_s", "missing required field (a phase that waits for an event needs a "
                                            "timeout)")
        if self.until is None and self.timeout_s is not None:
            raise FieldProblem("timeout_s", "only allowed together with until")
        if self.until == "tuned" and self.mode not in (None, "TUNE"):
            raise FieldProblem("until", f"waiting for 'tuned' needs mode TUNE, got {self.mode}")
        if self.ramp_c_per_min is not None and self.setpoint_c is None:
            raise FieldProblem("ramp_c_per_min", "a ramp needs setpoint_c (the ramp's target)")
        for i, d in enumerate(self.disturbance):
            if self.duration_s is not None and d.at_s > self.duration_s:
                raise FieldProblem(f"disturbance[{i + 1}].at_s",
                                   f"{d.at_s} s is after the end of its phase ({self.duration_s} s)")
        return self


class SensorTable(_Strict):
    lag_s: NonNegative = 0.0
    noise_sigma_c: NonNegative = 0.0
    offset_c: Finite = 0.0
    adc: Literal[ADC_KINDS] = "none"
    bits: Annotated[int, Field(strict=True, ge=MIN_ADC_BITS, le=MAX_ADC_BITS)] = 16
    ohm_per_count: Positive = 1.0 / 16.0
    ohm_at_zero: NonNegative = 0.0
    pullup_ohm: Positive = 4700.0
    r25_ohm: Positive = 100_000.0
    beta_k: Positive = 3950.0
    adc_noise_lsb: NonNegative = DEFAULT_ADC_NOISE_LSB


class ZoneTable(_Strict):
    name: StrictStr
    plc_zone: Annotated[int, Field(strict=True, ge=1)]
    channel: Annotated[int, Field(strict=True, ge=0)] = 0
    sensor: SensorTable = Field(default_factory=SensorTable)
    phase: list[PhaseTable] = Field(min_length=1)


class PlcTable(_Strict):
    scans_per_step: Annotated[int, Field(strict=True, ge=1)] = 1
    pv_path: Literal[PV_PATHS] = "real"
    output: Literal[OUTPUT_PATHS] = "analog"


class VariantTable(_Strict):
    name: StrictStr
    fuzzy: StrictBool | None = None
    write: dict[str, StrictBool | StrictInt | Finite] = Field(
        default_factory=dict,
        description="register writes at the start of the run (e.g. bHeatUpZone1 = true), before the phases'",
    )


class TargetTable(_Strict):
    """A figure the report judges: the measured metric against the reference's (paper) and our goal."""

    phase: StrictStr
    metric: StrictStr = Field(description="a metric name of metrics.json, e.g. overshoot_pct")
    zone: StrictStr | None = None
    variant: StrictStr | None = Field(None, description="only this variant (default: every variant)")
    paper: Finite | None = None
    goal: Finite | None = None
    better: Literal["lower", "higher"] = "lower"
    source: StrictStr = ""

    @model_validator(mode="after")
    def _rules(self) -> TargetTable:
        if self.paper is None and self.goal is None:
            raise FieldProblem("goal", "give paper, goal or both")
        return self


class ScenarioFile(_Strict):
    """A ThermoST scenario: plant, zones with sensors and phase programmes, controller variants."""

    name: StrictStr
    description: StrictStr
    reference: StrictStr = ""
    seed: Annotated[int, Field(strict=True, ge=0)] = 0
    dt_s: Positive = 0.1
    plc: PlcTable = Field(default_factory=PlcTable)
    plant: PlantTable
    zone: list[ZoneTable] = Field(min_length=1)
    variant: list[VariantTable] = Field(default_factory=list)
    target: list[TargetTable] = Field(default_factory=list)

    def plant_params(self) -> dict[str, Any]:
        return self.plant.model_dump(exclude={"model"}, exclude_none=True)

    @model_validator(mode="after")
    def _rules(self) -> ScenarioFile:
        try:
            plant = PLANT_MODELS[self.plant.model](**self.plant_params())
        except (ValueError, ZeroDivisionError) as exc:
            raise FieldProblem("plant", f"impossible plant parameters: {exc}") from None
        seen: set[int] = set()
        for i, z in enumerate(self.zone, start=1):
            if z.channel >= plant.channels:
                why = f"plant '{self.plant.model}' has {plant.channels} channel(s), got {z.channel}"
                raise FieldProblem(f"zone[{i}].channel", why)
            if z.plc_zone in seen:
                raise FieldProblem(f"zone[{i}].plc_zone", f"PLC zone {z.plc_zone} is used twice")
            seen.add(z.plc_zone)
            if self.plc.pv_path == "raw" and z.sensor.adc == "none":
                raise FieldProblem(f"zone[{i}].sensor.adc",
                                   "plc.pv_path = 'raw' needs an ADC front end (pt100 or ntc)")
        return self


# ---- error messages -----------------------------------------------------------------------------
def _key_path(loc: tuple, data: Any) -> tuple[str, Any]:
    """('zone', 0, 'phase', 2, 'x') -> 'zone[1].phase[3].x' (1-based, as in the file); the discriminator
    tags pydantic adds for unions (the plant model, the disturbance kind) are dropped."""
    parts: list[str] = []
    node = data
    for item in loc:
        if isinstance(item, int):
            parts[-1] += f"[{item + 1}]"
            node = node[item] if isinstance(node, list) and item < len(node) else None
        elif isinstance(node, dict) and item in node or not isinstance(node, dict) or not parts:
            parts.append(str(item))
            node = node.get(item) if isinstance(node, dict) else None
        elif item in PLANT_SCHEMAS or item in DISTURBANCE_FIELDS:
            continue  # union tag
        else:
            parts.append(str(item))
            node = None
    return ".".join(parts), node


def _type_name(value: Any) -> str:
    return type(value).__name__


WANTS = {"float_type": "float", "int_type": "int", "bool_type": "bool", "string_type": "str",
         "dict_type": "a table", "list_type": "an array of tables", "model_type": "a table"}


OPERATORS = {
    "greater_than": (">", "gt"),
    "greater_than_equal": (">=", "ge"),
    "less_than": ("<", "lt"),
    "less_than_equal": ("<=", "le"),
}


def first_error(errors: list[dict]) -> dict:
    """The error to report: an unknown key first (a typo also makes the intended key "missing")."""
    return next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])


def error_line(err: dict, data: Any) -> str:
    """One pydantic error as `<key path>: <why>`."""
    kind, loc, value, ctx = err["type"], tuple(err["loc"]), err.get("input"), err.get("ctx") or {}
    problem = ctx.get("error")
    if isinstance(problem, FieldProblem):
        path, _ = _key_path(loc, data)
        return f"{path + '.' if path else ''}{problem.key}: {problem.why}"
    path, _ = _key_path(loc, data)
    if kind == "extra_forbidden":
        _, parent = _key_path(loc[:-1], data)
        unused = [k for k in _known_keys(loc[:-1], data) if k not in (parent or {})]
        typo = difflib.get_close_matches(str(loc[-1]), unused, n=1)
        hint = f" (did you mean '{typo[0]}'?)" if typo else ""
        return f"{path}: unknown key{hint}"
    if kind == "missing":
        return f"{path}: missing required field"
    if kind == "union_tag_not_found":
        return f"{path}.{ctx.get('discriminator', '').strip(chr(39))}: missing required field"
    if kind == "union_tag_invalid":
        tag = ctx.get("discriminator", "").strip("'")
        expected = ctx.get("expected_tags", "").replace("'", "")
        return f"{path}.{tag}: must be one of {expected}, got {ctx.get('tag')!r}"
    if kind == "literal_error":
        return f"{path}: must be one of {ctx.get('expected', '').replace(chr(39), '')}, got {value!r}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        op, bound_key = OPERATORS[kind]
        bound = ctx.get(bound_key)
        return f"{path}: must be {op} {bound}, got {value!r}"
    if kind == "finite_number":
        return f"{path}: must be a finite number, got {value!r}"
    if kind in WANTS:
        if isinstance(value, float) and not math.isfinite(value) and kind != "float_type":
            return f"{path}: must be a finite number, got {value!r}"
        return f"{path}: must be {WANTS[kind]}, got {_type_name(value)} {value!r}"
    if kind == "too_short":
        return f"{path}: must be a non-empty array of tables"
    return f"{path}: {err['msg']}"


def _known_keys(loc: tuple, data: Any) -> list[str]:
    """Field names of the model at `loc` (for "did you mean")."""
    model: Any = ScenarioFile
    node = data
    for item in loc:
        if isinstance(item, int):
            node = node[item] if isinstance(node, list) else None
            continue
        if item in PLANT_SCHEMAS:
            model = PLANT_SCHEMAS[item]
            continue
        if item in DISTURBANCE_FIELDS:
            model = next(m for m in DISTURBANCE_MODELS if item in m.__name__)
            continue
        field = getattr(model, "model_fields", {}).get(item)
        node = node.get(item) if isinstance(node, dict) else None
        if field is None:
            return []
        model = _inner_model(field.annotation)
    return list(getattr(model, "model_fields", {}))


def _inner_model(annotation: Any) -> Any:
    for arg in (annotation, *typing.get_args(annotation)):
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            return arg
        inner = typing.get_args(arg)
        for a in inner:
            if isinstance(a, type) and issubclass(a, BaseModel):
                return a
    return None


def json_schema() -> dict:
    schema = ScenarioFile.model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "ThermoST scenario file (TOML)"
    return schema
