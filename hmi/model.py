"""What the panel knows about the application: zones, their registers and each register's metadata.

Everything comes from the register map (`modbus_bridge.regmap.load_register_map()`): the zone roles from
the harness' naming convention (`modbus_bridge.binding`), units/ranges/owner/group from each tag's
metadata (`Tag.meta`). Where a tag carries no metadata yet, a conservative reading of its comment is used
(unit from the comment, owner `client` for writable registers) so the panel still works, read-mostly.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from modbus_bridge.binding import ControllerCodes, ZoneBinding, resolve_zone
from modbus_bridge.regmap import RegisterMap, Tag

# extra roles the panel shows beyond the harness' (same naming convention, "{n}" = zone number); the
# harness' own (modbus_bridge.binding) include the tuning results noise_pp, t_filter (the filter TUNE sized)
# and ms, and the fuzzy adapter's Ms bound fz_ms_max, fz_ms_reachable, fz_gain_scale, fz_box_share
PANEL_ROLES: dict[str, str] = {
    "setpoint2": "fSetpointStandbyZone{n}",
    "sel_setpoint": "bSelSetpointZone{n}",
    "ramp": "bEnableRampingZone{n}",
    "w_work": "fWWorkZone{n}",
    "x_used": "fXUsedZone{n}",
    "tune_rule": "nTuneRuleZone{n}",
    "tune_rule_used": "nTuneRuleUsedZone{n}",
    "fit_rms": "fTuneFitRmsZone{n}",
    "tune_order": "nTuneOrderZone{n}",
    "lag_ratio": "fTuneLagRatioZone{n}",
    "ms_tuned": "fMsTunedZone{n}",
    "t_filter_used": "fTFilterUsedZone{n}",
    "w_min": "fWMinZone{n}",
    "w_max": "fWMaxZone{n}",
    "y_min": "fYMinZone{n}",
    "y_max": "fYMaxZone{n}",
    "y_tune": "fYTuneZone{n}",
    "end_tune_pct": "fEndTunePercentZone{n}",
    "td": "fTdZone{n}",
    "td_cool": "fTdCoolZone{n}",
    "tv_cool": "fTvCoolZone{n}",
    "weight": "fSetpointWeightZone{n}",
    "weight_cool": "fSetpointWeightCoolZone{n}",
    "fz_kp": "fFuzzyKpZone{n}",
    "fz_tn": "fFuzzyTnZone{n}",
    "fz_tv": "fFuzzyTvZone{n}",
    "kp_base": "fFuzzyKpBaseZone{n}",
    "tn_base": "fFuzzyTnBaseZone{n}",
    "tv_base": "fFuzzyTvBaseZone{n}",
    "td_eff": "fTdInUseZone{n}",  # beside kp_eff .. tv_eff: the set the PID ran on
    "fz_e": "fFuzzyEZone{n}",
    "fz_ec": "fFuzzyEcZone{n}",
    "fz_eq": "fFuzzyEqZone{n}",
    "fz_ecq": "fFuzzyEcqZone{n}",
    "fz_dkp": "fFuzzyDKpZone{n}",
    "fz_dki": "fFuzzyDKiZone{n}",
    "fz_dkd": "fFuzzyDKdZone{n}",
    "fz_universe": "fFuzzyUniverseZone{n}",
    "fz_status": "nFuzzyStatusZone{n}",
    "fz_error": "nFuzzyErrorIdZone{n}",
    "fz_preset": "nFuzzyPresetZone{n}",
    "fz_symmetric": "bFuzzySymmetricZone{n}",
    "fz_sign_band": "fFuzzySignBandZone{n}",
    "tau_norm": "fTauNormZone{n}",
    "heat_up": "bHeatUpZone{n}",
}
FUZZY_RULES = 4  # fFuzzyRule<k>StrengthZone<n> / nFuzzyRule<k>Zone<n>, k = 1..FUZZY_RULES
# the tuned set a reject restores (heating and cooling), in register order
GAIN_SET_ROLES = ("kp", "tn", "tv", "td", "weight", "kp_cool", "tn_cool", "tv_cool", "td_cool", "weight_cool")
MODE_BUTTONS = ("IDLE", "PASSIVE", "ACTIVE", "MANUAL", "TUNE", "RESET")
# groups of the parameter page when a tag carries no `group` metadata: first name pattern that matches
FALLBACK_GROUPS: tuple[tuple[str, str], ...] = (
    (r"fFuzzy|nFuzzy|bFuzzy", "fuzzy"),
    (r"f(Kp|Tn|Tv|Td|SetpointWeight)Cool", "pid_cooling"),
    (r"f(Kp|Tn|Tv|Td|SetpointWeight)Zone", "pid_heating"),
    (r"fY(Min|Max)|fYOnFailure|nReaction", "limits"),
    (r"fPwm", "pwm"),
    (r"fSetpoint|fW|fTStartUp|bSelSetpoint|bEnableRamp|bEnableSoftStart", "setpoint"),
    (r"fTemp|fRunaway|fWatch|fXM(in|ax)|dwAlarm(Supp|Reaction)|bAlarmLatch", "alarms"),
    (r"fYTune|fYStable|fTune|fEndTune|fSimc|nTuneRule", "tuning"),
    (r"fNtc|fRPullup|fRawRes|nRaw|bUseRaw|bRawFrom|fTFilter|bFilter", "sensor"),
)
UNIT_WORDS = ("degC/s", "degC/%", "%/degC", "degC", "%", "ohm", "s")


@dataclass
class Meta:
    """A tag's metadata as the panel uses it (from `Tag.meta`, or read from its comment)."""

    unit: str = ""
    min: float | None = None
    max: float | None = None
    default: float | None = None
    decimals: int = 2
    enum: dict[int, str] = field(default_factory=dict)
    owner: str = "plc"  # plc | client | command | input
    group: str = ""
    zone: int | None = None
    from_source: bool = False  # True: the application's metadata, False: read from the comment

    def check(self, value: float) -> str | None:
        """None if `value` may be written, else why not (the page refuses it)."""
        if not math.isfinite(value):
            return "not a finite number"
        if self.min is not None and value < self.min:
            return f"below the minimum {fmt(self.min)}{(' ' + self.unit) if self.unit else ''}"
        if self.max is not None and value > self.max:
            return f"above the maximum {fmt(self.max)}{(' ' + self.unit) if self.unit else ''}"
        if self.enum and int(value) not in self.enum:
            return f"not one of {', '.join(f'{k} {v}' for k, v in sorted(self.enum.items()))}"
        return None


def fmt(value: float | int | None, decimals: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        return f"{value:.{decimals}f}".rstrip("0").rstrip(".") if decimals else f"{value:.0f}"
    return str(value)


_ENUM_IN_COMMENT = re.compile(r"(-?\d+)\s+([A-Z][A-Z_]+)")
_ZONE_IN_NAME = re.compile(r"Zone(\d+)$")


def meta_of(tag: Tag) -> Meta:
    """The panel's view of a tag's metadata (the application's when present)."""
    src = getattr(tag, "meta", None)
    zone_m = _ZONE_IN_NAME.search(tag.name)
    zone = int(zone_m.group(1)) if zone_m else None
    if src is not None:
        return Meta(
            unit=getattr(src, "unit", "") or "",
            min=getattr(src, "min", None),
            max=getattr(src, "max", None),
            default=getattr(src, "default", None),
            decimals=int(getattr(src, "decimals", 2) or 0),
            enum=dict(getattr(src, "enum", {}) or {}),
            owner=getattr(src, "owner", "") or ("client" if tag.writable else "plc"),
            group=getattr(src, "group", "") or _fallback_group(tag.name),
            zone=getattr(src, "zone", None) if getattr(src, "zone", None) is not None else zone,
            from_source=True,
        )
    comment = tag.comment
    unit = next((u for u in UNIT_WORDS if re.search(rf"(^|[\s,(]){re.escape(u)}($|[\s,);])", comment)), "")
    enum = {int(k): v for k, v in _ENUM_IN_COMMENT.findall(comment)} if ":" in comment else {}
    return Meta(
        unit=unit,
        decimals=0 if tag.iec_type in ("INT", "DINT", "DWORD", "UINT", "WORD", "BOOL") else 2,
        enum=enum if len(enum) >= 2 else {},
        owner=("command" if "self-resetting" in comment else "client") if tag.writable else "plc",
        group=_fallback_group(tag.name),
        zone=zone,
    )


def _fallback_group(name: str) -> str:
    for pattern, group in FALLBACK_GROUPS:
        if re.match(pattern, name):
            return group
    return "status"


@dataclass
class ZoneModel:
    number: int
    binding: ZoneBinding
    tags: dict[str, str]  # role -> tag name (harness roles + panel roles that exist)
    rules: list[tuple[str, str]]  # (strength tag, rule code tag) of the firing fuzzy rules

    def has(self, role: str) -> bool:
        return role in self.tags

    def __getitem__(self, role: str) -> str:
        return self.tags[role]


@dataclass
class PanelModel:
    regmap: RegisterMap
    codes: ControllerCodes
    zones: list[ZoneModel]
    tune_states: dict[int, str]
    tune_rules: dict[int, str]
    meta: dict[str, Meta]

    def fast_tags(self) -> list[str]:
        """Read every poll cycle: what the overview, faceplate, trend and alarm pages show live."""
        roles = ("pv", "setpoint", "setpoint2", "w_work", "y", "mode", "state", "tune_state", "alarm",
                 "error", "kp_eff", "tn_eff", "tv_eff", "td_eff", "manual", "sel_setpoint", "ramp", "fuzzy",
                 "fz_e", "fz_ec", "fz_eq", "fz_ecq", "fz_dkp", "fz_dki", "fz_dkd", "fz_kp", "fz_tn", "fz_tv",
                 "kp", "tn", "tv", "td")
        names = [z[r] for z in self.zones for r in roles if z.has(r)]
        names += [n for z in self.zones for pair in z.rules for n in pair]
        return list(dict.fromkeys(names))

    def parameter_groups(self, zone: int) -> dict[str, list[str]]:
        """{group: parameter names} of the parameter page: every register of the zone a client sets (coils
        too), in register order; without metadata, no rows guessed to be status."""
        groups: dict[str, list[str]] = {}
        for name, meta in self.meta.items():
            if meta.zone == zone and meta.owner == "client" and (meta.from_source or meta.group != "status"):
                groups.setdefault(meta.group or "other", []).append(name)
        return groups

    def slow_tags(self) -> list[str]:
        """Read about once a second: every other register (parameters, identified plant, diagnostics)."""
        fast = set(self.fast_tags())
        return [n for n in self.regmap.tags if n not in fast]


def enum_names(type_name: str, prefix: str) -> dict[int, str]:
    """{code: member} of a library enumeration (st_lib), {} when it is not there."""
    from modbus_bridge.binding import enum_codes

    try:
        return {v: k for k, v in enum_codes(type_name, prefix).items()}
    except ValueError:
        return {}


def load_model(regmap: RegisterMap) -> PanelModel:
    """Zones 1, 2, ... as long as the application has them (at least zone 1)."""
    zones: list[ZoneModel] = []
    n = 1
    while True:
        try:
            binding = resolve_zone(regmap, n)
        except ValueError:
            break
        tags = dict(binding.tags)
        for role, pattern in PANEL_ROLES.items():
            name = pattern.format(n=n)
            if name in regmap and role not in tags:
                tags[role] = name
        rules = [
            (f"fFuzzyRule{k}StrengthZone{n}", f"nFuzzyRule{k}Zone{n}")
            for k in range(1, FUZZY_RULES + 1)
            if f"fFuzzyRule{k}StrengthZone{n}" in regmap and f"nFuzzyRule{k}Zone{n}" in regmap
        ]
        zones.append(ZoneModel(n, binding, tags, rules))
        n += 1
    if not zones:
        resolve_zone(regmap, 1)  # raises the clear error
    return PanelModel(
        regmap=regmap,
        codes=ControllerCodes.load(),
        zones=zones,
        tune_states=enum_names("E_CtrlTuneState", "eTUNE_STATE_"),
        tune_rules=enum_names("E_TuneRule", "eTUNE_RULE_"),
        meta={name: meta_of(tag) for name, tag in regmap.tags.items()},
    )
