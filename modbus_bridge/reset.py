"""A known state before every run on a PLC that may have run before (a long-running OpenPLC).

The known state is the application's own factory state: the values its registers and coils hold after
the first scans of a freshly loaded program. They are taken once from a reference copy of the program
(compiled in this process, never the PLC under test) and written to the PLC over Modbus:

1. every zone to mode RESET (output 0 at once) and its process value to the plant's start temperature,
   so a faulty PV of the previous run cannot latch an alarm again;
2. every client-writable register and coil back to its factory value (parameters, limits, tuned gains,
   fuzzy registers; self-resetting command coils and registers the PLC owns excepted);
3. a few scans, then the alarms acknowledged (command coil);
4. read back: mode and state RESET, alarm word as a fresh program shows it with that PV (0 unless the
   start temperature is outside a zone's factory limits), PV as written, every parameter as restored.
   A PLC that does not get there is retried a few times, then the run is refused with one line naming
   what differs.

Not reachable over Modbus: the identified plant of the last TUNE (Ks/Tu/Tg, owned by the PLC) and what
the fuzzy adapter derived from it stay until the next TUNE or a restart of the PLC.
"""

from __future__ import annotations

import asyncio
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

from .binding import ControllerCodes, ZoneBinding
from .client import PlcClient, PlcError
from .regmap import RegisterMap
from .scenario import Scenario

RESET_SCANS = 2
EXTERNAL_RESET_WAIT_S = 0.5
ATTEMPTS = 3
REL_TOLERANCE = 1e-6  # REAL read back through float32
# coils a client sets TRUE for one scan (the PLC clears them): never restored, pulsed where named below
COMMAND_COIL = re.compile(r"self-resetting|write TRUE", re.IGNORECASE)
PULSED_COILS = (re.compile(r"bAckZone\d+", re.IGNORECASE),)
# parameters checked on read back when the register map carries no owner metadata
VERIFIED_ROLES = ("kp", "tn", "tv", "td", "kp_cool", "tn_cool", "tv_cool", "setpoint", "manual", "fuzzy")


@dataclass
class FactoryState:
    """Client-writable tags of the application with the values a fresh program shows."""

    values: dict[str, float | int | bool] = field(default_factory=dict)
    program: str = ""

    def alarms_at(self, inputs: Mapping[str, float | int], alarm_tags: list[str]) -> dict[str, int]:
        """The alarm words a freshly loaded program shows with these inputs (mode RESET, PV): what a PLC
        in its factory state shows too (e.g. a start temperature outside a zone's factory limits)."""
        from plc.runtime.server import load_program

        app = load_program(self.program)
        located = {v.name: v for v in app.located}
        for _ in range(RESET_SCANS):
            app.scan()
        for name, value in inputs.items():
            located[name].set(value)
        for _ in range(2 * RESET_SCANS):
            app.scan()
        return {n: int(located[n].get()) for n in alarm_tags if n in located}

    @staticmethod
    def of_program(text: str, regmap: RegisterMap, scans: int = RESET_SCANS) -> FactoryState:
        from plc.runtime.server import load_program

        app = load_program(text)
        for _ in range(scans):
            app.scan()
        state = FactoryState(program=text)
        for var in app.located:
            tag = regmap.tags.get(var.name)
            if tag is None or not tag.writable:
                continue
            value = var.get()
            if tag.is_bit:
                state.values[tag.name] = bool(value)
            elif isinstance(value, float) and math.isfinite(value):
                state.values[tag.name] = value
            elif isinstance(value, int | bool):
                state.values[tag.name] = int(value)
        return state


def has_metadata(regmap: RegisterMap) -> bool:
    """True when the application's declarations carry `{owner=...; ...}` metadata (plc/app does; a bare
    program parses with every default, owner "client", no unit, no group)."""
    cached = getattr(regmap, "_thermost_has_meta", None)
    if cached is None:
        metas = [getattr(t, "meta", None) for t in regmap.tags.values()]
        cached = any(m is not None and (m.owner != "client" or m.group or m.unit) for m in metas)
        object.__setattr__(regmap, "_thermost_has_meta", cached)
    return cached


def owner_of(regmap: RegisterMap, name: str) -> str | None:
    if not has_metadata(regmap):
        return None
    return getattr(regmap[name].meta, "owner", None)  # type: ignore[attr-defined]


def is_command(regmap: RegisterMap, name: str) -> bool:
    owner = owner_of(regmap, name)
    if owner is not None:
        return owner == "command"
    tag = regmap[name]
    return tag.is_bit and bool(COMMAND_COIL.search(tag.comment))


def verified_tags(regmap: RegisterMap, factory: FactoryState, scenario: Scenario,
                  bindings: Mapping[int, ZoneBinding]) -> list[str]:
    """Parameters checked after the reset: every client-owned tag when the map says who owns what, else
    the controller gains, setpoint, manual value, fuzzy switch and every tag a scenario phase writes."""
    if has_metadata(regmap):
        return [n for n in factory.values if owner_of(regmap, n) == "client"]
    names = {b[r] for b in bindings.values() for r in VERIFIED_ROLES if b.has(r)}
    names |= {tag for z in scenario.zones for ph in z.phases for tag in ph.writes}
    return sorted(n for n in names if n in factory.values)


def _same(a: float | int | bool, b: float | int | bool) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        fa, fb = float(a), float(b)
        return fa == fb or abs(fa - fb) <= REL_TOLERANCE * max(abs(fa), abs(fb), 1.0)
    return a == b


async def _settle(client: PlcClient, stepped: bool, wait_s: float) -> None:
    if stepped:
        await client.step(RESET_SCANS)
    else:
        await asyncio.sleep(wait_s)


async def reset_to_known_state(
    client: PlcClient,
    scenario: Scenario,
    bindings: Mapping[int, ZoneBinding],
    codes: ControllerCodes,
    factory: FactoryState,
    *,
    stepped: bool,
    wait_s: float = EXTERNAL_RESET_WAIT_S,
) -> None:
    """Bring every zone of the scenario to the factory state in mode RESET; verified by reading back."""
    if "RESET" not in codes.modes:
        return
    regmap = client.regmap
    reset_code = codes.modes["RESET"]
    temps = scenario.build_plant().temperatures()
    pv_of = {z.plc_zone: float(temps[z.channel]) for z in scenario.zones}
    fixed: dict[str, float | int | bool] = {}
    for zone, b in bindings.items():
        fixed[b["mode"]] = reset_code
        fixed[b["pv"]] = pv_of[zone]
    restore = {
        n: v
        for n, v in factory.values.items()
        if n not in fixed and not is_command(regmap, n) and owner_of(regmap, n) != "plc"
    }
    pulses = {n: True for n in factory.values if any(rx.fullmatch(n) for rx in PULSED_COILS)}
    check = [n for n in verified_tags(regmap, factory, scenario, bindings) if n not in fixed]
    status = [b[r] for b in bindings.values() for r in ("state", "alarm") if b.has(r)]
    differs: list[str] = []
    expected_alarms: dict[str, int] | None = None
    for _attempt in range(ATTEMPTS):
        await client.write_tags(fixed)
        await client.write_tags(restore)
        await _settle(client, stepped, wait_s)
        if pulses:
            await client.write_tags(pulses)
            await _settle(client, stepped, wait_s)
        got = await client.read_tags(list(fixed) + check + status)
        differs = [f"{n} = {got[n]!r} (expected {v!r})" for n, v in fixed.items() if not _same(got[n], v)]
        differs += [f"{n} = {got[n]!r} (factory {factory.values[n]!r})" for n in check
                    if not _same(got[n], factory.values[n])]
        alarms = [b["alarm"] for b in bindings.values() if b.has("alarm")]
        if any(int(got[a]) for a in alarms) and expected_alarms is None:
            expected_alarms = factory.alarms_at(fixed, alarms) if factory.program else {}
        for b in bindings.values():
            if int(got[b["state"]]) != codes.states.get("RESET", reset_code):
                differs.append(f"{b['state']} = {codes.state_name(int(got[b['state']]))} (expected RESET)")
            expected = (expected_alarms or {}).get(b["alarm"], 0) if b.has("alarm") else 0
            if b.has("alarm") and int(got[b["alarm"]]) != expected:
                word = int(got[b["alarm"]])
                differs.append(f"{b['alarm']} = 0x{word:08X} (a fresh PLC shows 0x{expected:08X})")
        if not differs:
            return
    raise PlcError(
        f"{client.where} did not reach a known state after {ATTEMPTS} resets: {'; '.join(differs[:4])}"
    )
