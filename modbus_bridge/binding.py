"""Which register of the application plays which role for one controller zone.

Roles are found in the register map by the application's naming convention (tag name patterns with
the zone number), never by address; the enum codes for modes and states come from the library's
E_CtrlMode / E_CtrlState declarations (member order = numeric code, docs/library.md).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from .regmap import RegisterMap, RegisterMapError

ST_LIB = Path(__file__).resolve().parents[1] / "st_lib"

# role -> name patterns; "{n}" is the zone number. The first pattern that matches a tag wins.
ROLE_PATTERNS: dict[str, tuple[str, ...]] = {
    "pv": (r"fPvZone{n}", r"fXZone{n}", r"fActualZone{n}", r"fPv{n}", r"fX{n}"),
    # raw counts a Modbus client may write (the application's %IW hardware input is read-only)
    "pv_raw": (r"nPvRawModbusZone{n}", r"nPvRawZone{n}", r"nRawZone{n}", r"nAdcZone{n}", r"nRaw{n}"),
    # engineering unlock of the safety settings (docs/library.md: parameter protection)
    "unlock": (r"nUnlockKeyZone{n}",),
    # heartbeat: the PV writer changes it with every new PV (the PLC's stale-PV watchdog)
    "pv_seq": (r"nPvSeqZone{n}",),
    "pv_select": (r"bUseRawZone{n}", r"bPvRawZone{n}", r"bRawInputZone{n}"),
    "raw_from_modbus": (r"bRawFromModbusZone{n}",),
    "ntc_r25": (r"fNtcR25Zone{n}",),
    "ntc_beta": (r"fNtcBetaZone{n}",),
    "ntc_pullup": (r"fRPullupZone{n}",),
    "pt100_res_low": (r"fRawResLowZone{n}",),
    "pt100_res_high": (r"fRawResHighZone{n}",),
    "setpoint": (r"fSetpointZone{n}", r"fWZone{n}", r"fSpZone{n}", r"fW{n}"),
    "mode": (r"nModeZone{n}", r"nCtrlModeZone{n}", r"nMode{n}"),
    "manual": (r"fYManualZone{n}", r"fManualZone{n}", r"fYManual{n}"),
    "fuzzy": (r"bFuzzyZone{n}", r"bFuzzyEnableZone{n}", r"bEnableFuzzyZone{n}", r"bFuzzy{n}"),
    "y": (r"fYZone{n}", r"fOutZone{n}", r"fY{n}"),
    "pwm_heat": (r"bPwmHeatZone{n}", r"bHeatZone{n}", r"bPwmZone{n}", r"bPwm{n}"),
    "pwm_cool": (r"bPwmCoolZone{n}", r"bCoolZone{n}"),
    "state": (r"nStateZone{n}", r"nCtrlStateZone{n}", r"nState{n}"),
    # the time the controller counts per scan (its TASK interval): a stepped run's plant step must match it
    "task_cycle": (r"fTaskCycleTimeZone{n}",),
    "tune_state": (r"nTuneStateZone{n}", r"nTuneZone{n}"),
    "alarm": (r"dwAlarmZone{n}", r"nAlarmZone{n}", r"wAlarmZone{n}", r"dwAlarm{n}"),
    "error": (r"nErrorIdZone{n}", r"nErrorZone{n}", r"nErrorId{n}"),
    "ack": (r"bAckZone{n}", r"bAlarmAckZone{n}", r"bAck{n}"),
    "kp": (r"fKpZone{n}",),
    "tn": (r"fTnZone{n}",),
    "tv": (r"fTvZone{n}",),
    "td": (r"fTdZone{n}",),
    "kp_cool": (r"fKpCoolZone{n}",),
    "tn_cool": (r"fTnCoolZone{n}",),
    "tv_cool": (r"fTvCoolZone{n}",),
    "td_cool": (r"fTdCoolZone{n}",),
    "y_tune": (r"fYTuneZone{n}",),
    "ks": (r"fKsZone{n}",),
    "tu": (r"fTuZone{n}",),
    "tg": (r"fTgZone{n}",),
    "t_filter": (r"fTFilterTunedZone{n}",),
    "ms": (r"fMsTunedZone{n}",),
    # sensor noise peak-to-peak TUNE measured at rest (it sizes t_filter from it)
    "noise_pp": (r"fTuneNoisePpZone{n}",),
    # how long that noise held each value (the PV's update interval, on which t_filter is sized)
    "noise_interval": (r"fTuneNoiseIntervalZone{n}",),
    # order of the model TUNE identified: 1 FOPDT, n >= 2 n equal lags
    "order": (r"nTuneOrderZone{n}",),
    # rms residual of that model over the step record, % of the rise (0: not fitted)
    "fit_rms": (r"fTuneFitRmsZone{n}",),
    # the fuzzy adapter's Ms bound: the limit, the worst Ms over the gain sets it can reach, the scale of
    # the base gains and the share of the configured ratio box it kept for that
    "fz_ms_max": (r"fFuzzyMsMaxZone{n}",),
    "fz_ms_reachable": (r"fFuzzyMsReachableZone{n}",),
    "fz_gain_scale": (r"fFuzzyGainScaleZone{n}",),
    "fz_box_share": (r"fFuzzyBoxShareZone{n}",),
    # the model-based setpoint response: its phase and the plant its last limit phase saw
    "heatup_state": (r"nHeatUpStateZone{n}",),
    "heatup_tu": (r"fHeatUpTuSeenZone{n}",),
    "heatup_tg": (r"fHeatUpTgSeenZone{n}",),
    # the set the PID ran on (the cooling set while the output is below 0); maps without those registers:
    # the fuzzy adapter's heating set
    "kp_eff": (r"fKpInUseZone{n}", r"fFuzzyKpZone{n}", r"fKpEffZone{n}", r"fKpEffectiveZone{n}"),
    "tn_eff": (r"fTnInUseZone{n}", r"fFuzzyTnZone{n}", r"fTnEffZone{n}", r"fTnEffectiveZone{n}"),
    "tv_eff": (r"fTvInUseZone{n}", r"fFuzzyTvZone{n}", r"fTvEffZone{n}", r"fTvEffectiveZone{n}"),
}
# the application's commissioning key (nUnlockKeyValue in plc/app/gen_application.py; a test compares them)
UNLOCK_KEY = 0x5AFE
REQUIRED_ROLES = ("pv", "setpoint", "mode", "y", "state")
# the application's raw inputs span counts 0 .. 32767 (its nPvRaw register comment; nRawFullScale in ST)
RAW_FULL_SCALE = 32767
RAW_SENSOR_ROLES = {
    "ntc": ("ntc_r25", "ntc_beta", "ntc_pullup"),
    "pt100": ("pt100_res_low", "pt100_res_high"),
}


def enum_members(type_name: str, lib_dir: Path | None = None) -> list[str]:
    """Members of an enumerated TYPE declared in st_lib, in declaration order (= numeric code)."""
    directory = lib_dir or ST_LIB
    rx = re.compile(rf"\b{type_name}\s*:\s*\(([^)]*)\)", re.IGNORECASE)
    for path in sorted(directory.rglob("*.st")):
        text = re.sub(r"\(\*.*?\*\)", " ", path.read_text(encoding="utf-8"), flags=re.DOTALL)
        m = rx.search(text)
        if m:
            return [member.strip() for member in m.group(1).split(",") if member.strip()]
    raise RegisterMapError(f"enumerated type {type_name} not found in {directory}")


def enum_codes(type_name: str, prefix: str, lib_dir: Path | None = None) -> dict[str, int]:
    """{"ACTIVE": 2, ...}: members with their prefix (e.g. eCTRL_MODE_) removed."""
    out = {}
    for code, member in enumerate(enum_members(type_name, lib_dir)):
        short = member[len(prefix) :] if member.upper().startswith(prefix.upper()) else member
        out[short.upper()] = code
    return out


@dataclass
class ZoneBinding:
    zone: int
    tags: dict[str, str] = field(default_factory=dict)

    def has(self, role: str) -> bool:
        return role in self.tags

    def __getitem__(self, role: str) -> str:
        try:
            return self.tags[role]
        except KeyError:
            raise RegisterMapError(
                f"zone {self.zone}: no register for role '{role}' in the register map "
                f"(looked for {', '.join(p.format(n=self.zone) for p in ROLE_PATTERNS[role])})"
            ) from None


def resolve_zone(regmap: RegisterMap, zone: int) -> ZoneBinding:
    binding = ZoneBinding(zone=zone)
    lowered = {name.lower(): name for name in regmap.tags}
    for role, patterns in ROLE_PATTERNS.items():
        for pattern in patterns:
            rx = re.compile(pattern.format(n=zone), re.IGNORECASE)
            hit = next((orig for low, orig in lowered.items() if rx.fullmatch(low)), None)
            if hit is not None:
                binding.tags[role] = hit
                break
    for role in REQUIRED_ROLES:
        binding[role]  # raises with a clear message when missing
    return binding


@dataclass
class ControllerCodes:
    modes: dict[str, int]
    states: dict[str, int]

    @staticmethod
    def load(lib_dir: Path | None = None) -> ControllerCodes:
        return ControllerCodes(
            modes=enum_codes("E_CtrlMode", "eCTRL_MODE_", lib_dir),
            states=enum_codes("E_CtrlState", "eCTRL_STATE_", lib_dir),
        )

    def state_name(self, code: int) -> str:
        return next((k for k, v in self.states.items() if v == code), str(code))
