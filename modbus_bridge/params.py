"""`thermost params save|load --plc HOST:PORT FILE`: the parameter set of a PLC, read and written back.

For a PLC without persistent storage: after tuning, `save` keeps every client-owned parameter (gains,
limits, alarm settings, tuning and fuzzy registers - the register map's `owner=client`; not the operating
values mode, setpoint and manual output) in a JSON file; after a restart, `load` writes them back
(contiguous registers in one FC16 request, so a 32-bit value is never half-written) and reads them back:
a value the PLC refused (it validates every parameter and shows the value in use) is listed, exit 1.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime as dt
import json
import math
from pathlib import Path

from plc.cli import UserError, read_text_file, writable_file

from .binding import resolve_zone
from .client import PlcClient, PlcError
from .regmap import RegisterMap, RegisterMapError, load_register_map
from .reset import owner_of

FORMAT = "thermost parameters 1"
OPERATING_ROLES = ("mode", "setpoint", "manual")
APPLY_SCANS = 2
APPLY_WAIT_S = 0.5
REL_TOLERANCE = 1e-6
MAX_ZONES = 16


def parameter_names(regmap: RegisterMap) -> list[str]:
    """Client-owned registers and coils, without the operating values of any zone."""
    operating: set[str] = set()
    for zone in range(1, MAX_ZONES + 1):
        try:
            binding = resolve_zone(regmap, zone)
        except RegisterMapError:
            continue
        operating |= {binding[r] for r in OPERATING_ROLES if binding.has(r)}
    names = [n for n, t in regmap.tags.items() if t.writable and owner_of(regmap, n) == "client"]
    if not names:
        raise UserError("the register map has no owner metadata: cannot tell parameters from status")
    return sorted(n for n in names if n not in operating)


def _unit(regmap: RegisterMap, name: str) -> str:
    return getattr(getattr(regmap[name], "meta", None), "unit", "")


def _plc(text: str) -> tuple[str, int]:
    from .runner import parse_host_port

    try:
        return parse_host_port(text)
    except ValueError as exc:
        raise UserError(str(exc)) from None


async def _save(host: str, port: int, regmap: RegisterMap) -> dict:
    names = parameter_names(regmap)
    async with PlcClient(host, port, regmap) as client:
        values = await client.read_tags(names)
    from importlib.metadata import version

    return {
        "format": FORMAT,
        "plc": f"{host}:{port}",
        "saved": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "tool": f"thermost {version('thermost')}",
        "parameters": {
            n: {"value": values[n], "location": regmap[n].location, "unit": _unit(regmap, n)} for n in names
        },
    }


def read_params_file(name: str, regmap: RegisterMap) -> dict[str, float | int | bool]:
    try:
        doc = json.loads(read_text_file(name, "parameter file"))
    except json.JSONDecodeError as exc:
        raise UserError(f"{name}: not JSON: {exc}") from None
    valid = isinstance(doc, dict) and doc.get("format") == FORMAT
    if not valid or not isinstance(doc.get("parameters"), dict):
        raise UserError(f"{name}: not a parameter file of `thermost params save` (format {FORMAT!r})")
    allowed = set(parameter_names(regmap))
    out: dict[str, float | int | bool] = {}
    for tag, entry in doc["parameters"].items():
        value = entry.get("value") if isinstance(entry, dict) else None
        if tag not in regmap:
            raise UserError(f"{name}: {tag} is not in the register map of this application")
        if tag not in allowed:
            raise UserError(f"{name}: {tag} is not a parameter a client may write")
        if isinstance(value, bool) != regmap[tag].is_bit or not isinstance(value, int | float):
            raise UserError(f"{name}: {tag}: {value!r} is not a {regmap[tag].iec_type}")
        if isinstance(value, float) and not math.isfinite(value):
            raise UserError(f"{name}: {tag}: {value} is not a finite number")
        out[tag] = value
    return out


def _same(a: float | int | bool, b: float | int | bool) -> bool:
    fa, fb = float(a), float(b)
    return fa == fb or abs(fa - fb) <= REL_TOLERANCE * max(abs(fa), abs(fb), 1.0)


async def _load(host: str, port: int, regmap: RegisterMap, values: dict) -> list[str]:
    async with PlcClient(host, port, regmap) as client:
        await client.write_tags(values)
        if await client.stepped():
            await client.step(APPLY_SCANS)
        else:
            await asyncio.sleep(APPLY_WAIT_S)
        got = await client.read_tags(list(values))
    return [
        f"{n}: wrote {values[n]!r}, the PLC uses {got[n]!r}" for n in values if not _same(got[n], values[n])
    ]


def main_params(args: argparse.Namespace) -> int:
    host, port = _plc(args.plc)
    try:
        regmap = load_register_map()
    except RegisterMapError as exc:
        raise UserError(str(exc)) from None
    try:
        if args.action == "save":
            target = writable_file(args.file)
            doc = asyncio.run(_save(host, port, regmap))
            target.parent.mkdir(parents=True, exist_ok=True)
            Path(target).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
            print(f"saved {len(doc['parameters'])} parameters of {host}:{port} to {target}")
            return 0
        values = read_params_file(args.file, regmap)
        refused = asyncio.run(_load(host, port, regmap, values))
    except PlcError as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:
        raise UserError(f"{args.file}: cannot write: {exc.strerror or exc}") from None
    print(f"loaded {len(values) - len(refused)} of {len(values)} parameters into {host}:{port}")
    for line in refused:
        print(f"refused: {line}")
    return 1 if refused else 0
