"""Writes plc/app/P_ThermoST.st, the OpenPLC application PROGRAM, from the tag table plc/app/tags.tsv.

Every zone repeats the same register block, so the table lists it once: one row per located variable
with its place (section, offset), IEC type, how the program wires it, and the metadata the register map
carries (unit, range, default per zone as `zone1|zone2`, decimals, enum texts, owner, group). The
metadata goes into each declaration's comment as `{key=value; ...}`, where modbus_bridge.regmap reads it.
Run `python plc/app/gen_application.py` after editing the table or this file; a test checks the output
is up to date.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).parent
OUT = HERE / "P_ThermoST.st"
TABLE = HERE / "tags.tsv"
BODY = HERE / "zone_body.st.in"
MD_ZONE, MW_ZONE, FUZZY_MD, FUZZY_MD_ZONE, FUZZY_COIL_BYTE = 100, 20, 200, 50, 4
META_KEYS = ("unit", "min", "max", "default", "dec", "enum", "owner", "group")


@dataclass(frozen=True)
class Zone:
    n: int
    title: str
    sensor: str  # "ntc" or "pt100"


ZONES = [
    Zone(1, "nozzle (seed 000 / seed 002 hot end: heater only, 100 kOhm NTC on a divider)", "ntc"),
    Zone(2, "forming platform (seed 000: compressor cooling + heater, PT100)", "pt100"),
]


def read_table() -> list[dict[str, str]]:
    with TABLE.open(newline="") as fh:
        return list(csv.DictReader(fh, delimiter="\t", quoting=csv.QUOTE_NONE))


def rows_of(table: list[dict[str, str]], z: Zone, *sections: str) -> list[dict[str, str]]:
    return [r for r in table if r["section"] in sections and r["zones"] in ("", str(z.n))]


def zone_default(row: dict[str, str], z: Zone) -> str:
    values = row["default"].split("|")
    return values[min(z.n, len(values)) - 1]


def st_literal(value: str, iec_type: str) -> str:
    if iec_type == "REAL":
        return repr(float(value))
    if iec_type == "DWORD":
        return f"16#{int(value):08X}"
    if iec_type == "BOOL":
        return "TRUE" if value == "1" else "FALSE"
    return str(int(value))


def location(row: dict[str, str], z: Zone) -> str:
    off, sec = int(row["offset"]), row["section"]
    if sec == "md":
        return f"%MD{(z.n - 1) * MD_ZONE + off}"
    if sec == "mw":
        return f"%MW{(z.n - 1) * MW_ZONE + off}"
    if sec == "iw":
        return f"%IW{z.n - 1 + off}"
    if sec == "coil":
        return f"%QX{z.n - 1 + 2 * (off // 8)}.{off % 8}"
    if sec == "fuzzy_md":
        return f"%MD{FUZZY_MD + FUZZY_MD_ZONE * (z.n - 1) + off}"
    if sec == "fuzzy_coil":
        return f"%QX{FUZZY_COIL_BYTE}.{off + z.n - 1}"
    raise ValueError(f"{TABLE.name}: unknown section {sec!r} of {row['name']}")


def declaration(row: dict[str, str], name: str, where: str, z: Zone | None) -> str:
    meta = dict(row)
    if z is not None and row["default"]:
        meta["default"] = zone_default(row, z)
    tail = "; ".join(f"{k}={meta[k]}" for k in META_KEYS if meta.get(k))
    return f"    {name} AT {where} : {row['type']}; (* {row['description']} {{{tail}}} *)"


def wire(row: dict[str, str]) -> tuple[str, str]:
    kind, _, field = row["wire"].partition(":")
    return kind, field or row["name"]


def sync_block(row: dict[str, str], n: int) -> str:
    """Instance name of a register's sync block (iec2c crashes on long multi-name FB declarations)."""
    return f"fbSync{row['name'].lstrip('fdw')}Zone{n}"


def zone_decls(table: list[dict[str, str]], z: Zone) -> tuple[list[str], list[str]]:
    """(located declarations, internal declarations) of zone z."""
    n = z.n
    loc = [f"    (* ---- zone {n}: {z.title} ---- *)"]
    for r in rows_of(table, z, "md", "mw", "iw", "coil", "fuzzy_md", "fuzzy_coil"):
        loc.append(declaration(r, f"{r['name']}Zone{n}", location(r, z), z))
    params = rows_of(table, z, "md")
    cfg = [r for r in rows_of(table, z, "coil") if wire(r)[0] == "cfg" and r["default"]]
    defaults = ", ".join(
        f"{wire(r)[1]} := {st_literal(zone_default(r, z), r['type'])}"
        for r in params + cfg if wire(r)[0] in ("param", "cfg") and r["type"] == "REAL"
    )
    sync_blocks = [
        f"    {sync_block(r, n)} : {'FB_ParamSyncReal' if r['type'] == 'REAL' else 'FB_ParamSyncDword'};"
        for r in params if wire(r)[0] == "param"
    ]
    internal = [
        f"    sParZone{n} : ST_ControllerParameter := ({defaults});",
        f"    fbZone{n} : FB_TempController;",
        f"    fXZone{n}, fResZone{n} : REAL;",
        f"    nRawZone{n} : INT;",
        f"    bRawOpenZone{n}, bRawShortZone{n} : BOOL;",
        f"    eModeZone{n} : E_CtrlMode := eCTRL_MODE_IDLE;",
        f"    bRejectedZone{n}, bOneRejectZone{n}, bParamRefusedZone{n} : BOOL;",
        *sync_blocks,
        f"    sFuzzyParZone{n} : ST_FuzzyParameter;",
        f"    fbFuzzyZone{n} : FB_FuzzyGainAdapter;",
        f"    bFuzzyInitZone{n}, bFuzzyLoadReqZone{n}, bFuzzyOkZone{n} : BOOL;",
        f"    nFuzzyPresetLoadedZone{n} : DINT := -1;",
        f"    fFuzzyTuPrevZone{n} : REAL;",
        f"    fUnlockRemainZone{n} : REAL;",
        f"    bWrittenZone{n} : BOOL;",
        f"    bRefInvalidZone{n}, bRefLockedZone{n}, bRefDisableZone{n} : BOOL;",
    ]
    return loc, internal


def zone_init(table: list[dict[str, str]], z: Zone) -> list[str]:
    """First scan: modes off, coils to their defaults; the other client registers only on a blank store."""
    n = z.n
    lines = [f"    nModeZone{n} := 0;"]
    # MatIEC refuses DWORD and BOOL values in a structure initialiser: these start here instead
    lines += [f"    sParZone{n}.{wire(r)[1]} := {st_literal(zone_default(r, z), r['type'])};"
              for r in rows_of(table, z, "md") if wire(r)[0] == "param" and r["type"] == "DWORD"]
    kept = []
    for r in rows_of(table, z, "md", "mw", "coil"):
        if r["owner"] != "client" or not r["default"] or wire(r)[0] == "param" or r["name"] == "nMode":
            continue
        assign = f"{r['name']}Zone{n} := {st_literal(zone_default(r, z), r['type'])};"
        (lines if r["section"] == "coil" else kept).append(f"    {assign}")
    return lines + ["    IF NOT bStoreKept THEN", *("  " + a for a in kept), "    END_IF;"]


def sync_lines(table: list[dict[str, str]], z: Zone) -> list[str]:
    n, out = z.n, []
    for r in rows_of(table, z, "md", "coil"):
        kind, field = wire(r)
        reg, fb = f"{r['name']}Zone{n}", sync_block(r, n)
        if kind == "param" and r["type"] == "REAL":
            out.append(f"  {fb}(bLoad := bLoadStore, fInUse := fbZone{n}.sValid.{field}, fRegister := {reg},"
                       f" fParam := sParZone{n}.{field}, bAnyRefused := bRejectedZone{n});")
        elif kind == "param":
            out.append(f"  {fb}(bLoad := bLoadStore, dwInUse := fbZone{n}.sValid.{field},"
                       f" dwRegister := {reg}, dwParam := sParZone{n}.{field});")
        elif kind == "cfg":
            out.append(f"  sParZone{n}.{field} := {reg};")
    return out


def status_lines(table: list[dict[str, str]], z: Zone) -> list[str]:
    n, out = z.n, []
    for r in rows_of(table, z, "md", "coil", "fuzzy_md"):
        kind, field = wire(r)
        if kind == "fuzzy_out" and field != r["name"]:
            out.append(f"  {r['name']}Zone{n} := fbFuzzyZone{n}.{field};")
        elif kind == "out":
            out.append(f"  {r['name']}Zone{n} := fbZone{n}.{field};")
        elif kind in ("inuse", "param"):
            out.append(f"  {r['name']}Zone{n} := fbZone{n}.sValid.{field};")
        elif kind == "cfg":
            out.append(f"  {r['name']}Zone{n} := fbZone{n}.sValid.{field};")
    return out


def written_lines(table: list[dict[str, str]], z: Zone) -> list[str]:
    """bWrittenZone<n>: a client wrote a synchronised parameter register in this scan."""
    n = z.n
    fbs = [f"{sync_block(r, n)}.bWritten" for r in rows_of(table, z, "md") if wire(r)[0] == "param"]
    lines = [f"  bWrittenZone{n} := {fbs[0]}"]
    lines += [f"    OR {fb}" for fb in fbs[1:]]
    lines[-1] += ";"
    return lines


def fuzzy_registers(table: list[dict[str, str]], z: Zone, direction: str) -> list[str]:
    """Fuzzy parameter registers from (direction 'show') or into ('apply') sFuzzyParZone<n>."""
    n, out = z.n, []
    for r in rows_of(table, z, "fuzzy_md"):
        kind, field = wire(r)
        if kind != "fuzzy_param" or field == r["name"]:
            continue
        reg, par = f"{r['name']}Zone{n}", f"sFuzzyParZone{n}.{field}"
        out.append(f"    {reg} := {par};" if direction == "show" else f"    {par} := {reg};")
    return out


def zone_body(table: list[dict[str, str]], z: Zone) -> list[str]:
    template = BODY.read_text()
    sensor_start, sensor_end = template.index("(*@sensor"), template.index("(*@end sensor*)")
    sensors = template[sensor_start:sensor_end].split("(*@sensor ")[1:]
    chosen = next(s.split("*)", 1)[1] for s in sensors if s.startswith(z.sensor))
    text = template[:sensor_start] + chosen.strip("\n") + template[sensor_end + len("(*@end sensor*)"):]
    fills = {
        "SYNC": sync_lines(table, z),
        "STATUS": status_lines(table, z),
        "WRITTEN": written_lines(table, z),
        "FUZZY_SHOW": fuzzy_registers(table, z, "show"),
        "FUZZY_APPLY": fuzzy_registers(table, z, "apply"),
        "FUZZY_DEFAULTS": [
            f"      {r['name']}Zone{z.n} := {r['default']};"
            for r in rows_of(table, z, "fuzzy_md") if r["default"] and wire(r)[1] == r["name"]
        ],
    }
    lines: list[str] = []
    for line in text.replace("{n}", str(z.n)).replace("{title}", z.title).split("\n"):
        key = line.strip().removeprefix("(*@").removesuffix("*)")
        lines += fills[key] if key in fills else [line]
    return lines


def generate() -> str:
    table = read_table()
    header = (HERE / "P_ThermoST.header.txt").read_text().rstrip("\n").split("\n")
    out = [*header, "PROGRAM P_ThermoST"]
    internal: list[str] = []
    for z in ZONES:
        loc, inner = zone_decls(table, z)
        out += ["  VAR", *loc, "  END_VAR"]
        internal += inner
    for r in (r for r in table if r["section"] == "global_mw"):
        out += ["  VAR", declaration(r, r["name"], f"%MW{r['offset']}", None), "  END_VAR"]
    out += ["  VAR", "    bInitDone, bStoreKept, bLoadStore : BOOL;", *internal, "  END_VAR",
            "  VAR CONSTANT",
            "    nStoreSignatureValue : INT := 16#7E57; (* first scan: kept by a persistent store *)",
            "    nRawFullScale : INT := 32767;",
            "    fROpenCircuit : REAL := 1.0E9; (* NTC divider: resistance of an open input, ohm *)",
            "    dwParamErrorBit : DWORD := 16#00010000;",
            "    nUnlockKeyValue : DINT := 16#5AFE; (* engineering unlock key, set at commissioning *)",
            "    fUnlockTime : REAL := 600.0; (* s an engineering unlock lasts *)",
            "    nRefusalInvalid : INT := 1;",
            "    nRefusalLocked : INT := 2;",
            "    nRefusalDisable : INT := 4;",
            "    fFuzzyEcFilterRatio : REAL := 0.25; (* ec filter time / dead time *)",
            "  END_VAR", "",
            "  bLoadStore := FALSE;",
            "  IF NOT bInitDone THEN",
            "    bStoreKept := nStoreSignature = nStoreSignatureValue;",
            "    nStoreSignature := nStoreSignatureValue;",
            "    bLoadStore := bStoreKept;"]
    for z in ZONES:
        out += zone_init(table, z)
    out += ["    bInitDone := TRUE;", "  END_IF;", ""]
    for z in ZONES:
        out += zone_body(table, z) + [""]
    out.append("END_PROGRAM")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    OUT.write_text(generate())
    print(f"wrote {OUT}")
