"""Checks before a closed-loop run starts: every register and mode the scenario needs exists in the
application, and a stepped run's plant step is the PLC time its scans count. Each problem is one clear
line (RegisterMapError)."""

from __future__ import annotations

from .binding import RAW_FULL_SCALE, ControllerCodes, ZoneBinding
from .regmap import RegisterMap, RegisterMapError
from .scenario import Scenario, Zone


def required_roles(scenario: Scenario, zone: Zone) -> list[str]:
    roles = ["pv", "setpoint", "mode", "state"]
    roles.append("pwm_heat" if scenario.output_path == "pwm" else "y")
    if scenario.pv_path == "raw":
        roles.append("pv_raw")
    if any(p.fuzzy is not None for p in zone.phases) or any(v.fuzzy is not None for v in scenario.variants):
        roles.append("fuzzy")
    if any(p.manual_pct is not None for p in zone.phases):
        roles.append("manual")
    return roles


def check_bindings(
    scenario: Scenario,
    bindings: dict[int, ZoneBinding],
    codes: ControllerCodes,
    regmap: RegisterMap,
    stepped: bool = True,
) -> None:
    """Before anything starts: every register and mode the scenario needs exists, and a stepped run's plant
    step is the PLC time its scans count (else one clear line)."""
    for zone in scenario.zones:
        if zone.plc_zone not in bindings:
            raise RegisterMapError(
                f"zone '{zone.name}': the application has no controller zone {zone.plc_zone}"
            )
        b = bindings[zone.plc_zone]
        for role in required_roles(scenario, zone):
            b[role]
        if scenario.pv_path == "raw":
            if not regmap[b["pv_raw"]].writable:
                raise RegisterMapError(
                    f"zone '{zone.name}': raw input {b['pv_raw']} is read-only for a Modbus client"
                )
            if b.has("ntc_r25") and zone.sensor.adc.full_scale != RAW_FULL_SCALE:
                raise RegisterMapError(
                    f"zone '{zone.name}': the application's raw inputs span 0..{RAW_FULL_SCALE}: "
                    f"set sensor bits = {RAW_FULL_SCALE.bit_length()}"
                )
        if stepped:
            check_step_matches_task_cycle(scenario, zone, b, regmap)
        for ph in zone.phases:
            for tag in ph.writes:
                client_tag = regmap[tag]  # raises "tag ... is not in the register map"
                if not client_tag.writable:
                    raise RegisterMapError(f"zone '{zone.name}', phase '{ph.name}': {tag} is read-only")
            if ph.mode is not None and ph.mode not in codes.modes:
                raise RegisterMapError(
                    f"zone '{zone.name}', phase '{ph.name}': mode {ph.mode} is not a member "
                    f"of E_CtrlMode ({', '.join(codes.modes)})"
                )
            if ph.until == "tuned" and "TUNED" not in codes.states:
                raise RegisterMapError("E_CtrlState has no TUNED member: cannot wait for the end of tuning")


STEP_MATCH_REL = 1e-6


def check_step_matches_task_cycle(
    scenario: Scenario, zone: Zone, b: ZoneBinding, regmap: RegisterMap
) -> None:
    """Stepped runs: the plant steps dt_s while the PLC scans scans_per_step times, and the controller
    counts its task cycle per scan; if the two disagree every identified time and every timer is off by
    their ratio."""
    if not b.has("task_cycle"):
        return
    tag = b["task_cycle"]
    cycle = next((ph.writes[tag] for ph in zone.phases[:1] if tag in ph.writes), regmap[tag].meta.default)
    if cycle is None:
        return
    plc_time = scenario.scans_per_step * float(cycle)
    if abs(plc_time - scenario.dt_s) > STEP_MATCH_REL * max(scenario.dt_s, plc_time):
        raise RegisterMapError(
            f"zone '{zone.name}': a plant step of {scenario.dt_s:g} s is {scenario.scans_per_step} "
            f"scan(s) of {float(cycle):g} s ({tag}) = {plc_time:g} s of PLC time: set [plc] scans_per_step = "
            f"{scenario.dt_s / float(cycle):g} (or dt_s = {plc_time:g})"
        )
