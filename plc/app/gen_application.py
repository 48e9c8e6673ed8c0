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
import re
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).parent
OUT = HERE / "P_ThermoST.st"
TABLE = HERE / "tags.tsv"
BLOCK_TEMPLATE = HERE / "FB_TempZone.st.in"
BLOCK = HERE.parents[1] / "st_lib" / "registers" / "FB_TempZone.st"
LINE_WIDTH = 116
MD_ZONE, MW_ZONE, FUZZY_MD, FUZZY_MD_ZONE, FUZZY_COIL_BYTE = 100, 20, 200, 50, 4
EXT_MD, EXT_MD_ZONE = 300, 50  # the zone's second block of 32-bit registers, after the fuzzy adapter's
PARAM_MD = ("md", "ext_md")
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
    if sec == "ext_md":
        return f"%MD{EXT_MD + EXT_MD_ZONE * (z.n - 1) + off}"
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


def sync_block(row: dict[str, str]) -> str:
    """Instance name of a register's sync block (iec2c crashes on long multi-name FB declarations)."""
    return f"fbSync{row['name'].lstrip('fdw')}"


def param_defaults(table: list[dict[str, str]], z: Zone) -> str:
    params = rows_of(table, z, *PARAM_MD) + [r for r in rows_of(table, z, "coil") if r["default"]]
    return ", ".join(f"{wire(r)[1]} := {st_literal(zone_default(r, z), r['type'])}"
                     for r in params if wire(r)[0] in ("param", "cfg") and r["type"] == "REAL")


def zone_init(table: list[dict[str, str]], z: Zone) -> list[str]:
    """First scan: modes off, coils to their defaults; the other client registers only on a blank store."""
    n = z.n
    lines = [f"    nModeZone{n} := 0;"]
    # MatIEC refuses DWORD and BOOL values in a structure initialiser: these start here instead
    lines += [f"    sParZone{n}.{wire(r)[1]} := {st_literal(zone_default(r, z), r['type'])};"
              for r in rows_of(table, z, *PARAM_MD) if wire(r)[0] == "param" and r["type"] == "DWORD"]
    kept = []
    for r in rows_of(table, z, *PARAM_MD, "mw", "coil"):
        if r["owner"] != "client" or not r["default"] or wire(r)[0] == "param" or r["name"] == "nMode":
            continue
        assign = f"{r['name']}Zone{n} := {st_literal(zone_default(r, z), r['type'])};"
        (lines if r["section"] == "coil" else kept).append(f"    {assign}")
    return lines + ["    IF NOT bStoreKept THEN", *("  " + a for a in kept), "    END_IF;"]


def fills(table: list[dict[str, str]]) -> dict[str, list[str]]:
    """The generated parts of the zone block's body, by their (*@KEY*) placeholder."""
    rows = [r for r in table if r["zones"] == ""]
    sync, status, show, apply = [], [], [], []
    for r in rows:
        kind, field = wire(r)
        name, fb = r["name"], sync_block(r)
        if kind == "param" and r["type"] == "REAL":
            sync.append(f"  {fb}(bLoad := bLoadStore, fInUse := fbCtrl.sValid.{field}, fRegister := {name},"
                        f" fParam := sPar.{field}, bAnyRefused := bRejected);")
        elif kind == "param":
            sync.append(f"  {fb}(bLoad := bLoadStore, dwInUse := fbCtrl.sValid.{field},"
                        f" dwRegister := {name}, dwParam := sPar.{field});")
        elif kind == "cfg":
            sync.append(f"  sPar.{field} := {name};")
        if kind == "fuzzy_out" and field != name:
            status.append(f"  {name} := fbFuzzy.{field};")
        elif kind == "out":
            status.append(f"  {name} := fbCtrl.{field};")
        elif kind in ("inuse", "param", "cfg") and r["section"] in (*PARAM_MD, "coil"):
            status.append(f"  {name} := fbCtrl.sValid.{field};")
        if kind == "fuzzy_param" and field != name:
            show.append(f"    {name} := sFuzzyPar.{field};")
            apply.append(f"    sFuzzyPar.{field} := {name};")
    written = [f"{sync_block(r)}.bWritten" for r in rows
               if wire(r)[0] == "param" and r["section"] in PARAM_MD]
    return {
        "SYNC": sync, "STATUS": status, "FUZZY_SHOW": show, "FUZZY_APPLY": apply,
        "WRITTEN": [f"  bWritten := {written[0]}", *(f"    OR {w}" for w in written[1:-1]),
                    f"    OR {written[-1]};"],
        "FUZZY_DEFAULTS": [f"      {r['name']} := {r['default']};" for r in rows
                           if r["section"] == "fuzzy_md" and r["default"] and wire(r)[1] == r["name"]],
    }


def block_ports(table: list[dict[str, str]], body: str) -> tuple[list[dict[str, str]], list[dict[str, str]]]:
    """(read-only, read-write) registers of the zone block: those its body names, in table order."""
    used = [r for r in table if r["zones"] == "" and r["section"] != "global_mw"
            and re.search(rf"(?<![\w.]){r['name']}(?!\w)", body)]
    written = [r for r in used if re.search(rf"(?<![\w.]){r['name']}\s*:=|Register := {r['name']}\b", body)]
    return [r for r in used if r not in written], written


def zone_block(table: list[dict[str, str]]) -> tuple[str, list[dict[str, str]]]:
    """(FB_TempZone's source, its registers in the order of its ports)."""
    fill = fills(table)
    template = BLOCK_TEMPLATE.read_text()
    body = template[template.index("\n\n", template.index("VAR CONSTANT")):]
    for key, lines in fill.items():
        body = body.replace(f"(*@{key}*)", "\n".join(lines).strip())
    inputs, inouts = block_ports(table, body)
    sensors = [r for r in table if wire(r)[0] == "sensor"]
    fill["INPUTS"] = [f"    {r['name']} : {r['type']}; (* {r['description']} *)" for r in sensors + inputs]
    fill["INOUTS"] = [f"    {r['name']} : {r['type']}; (* {r['description']} *)" for r in inouts]
    fill["SYNC_BLOCKS"] = [f"    {sync_block(r)} : FB_ParamSync{'Real' if r['type'] == 'REAL' else 'Dword'};"
                           for r in table if r["zones"] == "" and wire(r)[0] == "param"]
    out: list[str] = []
    for line in template.split("\n"):
        out += fill.get(line.strip().removeprefix("(*@").removesuffix("*)"), [line])
    return "\n".join(out), sensors + inputs + inouts


def zone_call(table: list[dict[str, str]], z: Zone) -> list[str]:
    n, ports = z.n, zone_block(table)[1]
    args = ["bLoadStore := bLoadStore", "bStoreKept := bStoreKept", "nUnlockKeyValue := nUnlockKeyValue",
            f"bNtcDivider := {'TRUE' if z.sensor == 'ntc' else 'FALSE'}",
            "bNeighbourStep := " + " OR ".join(f"fbZone{o.n}.bStepping" for o in ZONES if o.n != n),
            f"sPar := sParZone{n}"]
    args += [f"{r['name']} := {r['name']}Zone{n}" for r in ports if r["zones"] in ("", str(n))]
    lines, line = [], f"  fbZone{n}("
    for i, a in enumerate(args):
        piece = a + (");" if i == len(args) - 1 else ", ")
        if len(line) + len(piece) > LINE_WIDTH:
            lines.append(line.rstrip())
            line = "    "
        line += piece
    return [f"  (* ================= zone {n}: {z.title} ================= *)", *lines, line]


def zone_decls(table: list[dict[str, str]], z: Zone) -> tuple[list[str], list[str]]:
    """(located declarations, internal declarations) of zone z."""
    loc = [f"    (* ---- zone {z.n}: {z.title} ---- *)"]
    loc += [declaration(r, f"{r['name']}Zone{z.n}", location(r, z), z)
            for r in rows_of(table, z, "md", "mw", "iw", "coil", "fuzzy_md", "fuzzy_coil", "ext_md")]
    internal = [f"    sParZone{z.n} : ST_ControllerParameter := ({param_defaults(table, z)});",
                f"    fbZone{z.n} : FB_TempZone;"]
    return loc, internal


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
            "    nUnlockKeyValue : DINT := 16#5AFE; (* engineering unlock key, set at commissioning *)",
            "  END_VAR", "",
            "  bLoadStore := FALSE;",
            "  IF NOT bInitDone THEN",
            "    bStoreKept := nStoreSignature = nStoreSignatureValue;",
            "    nStoreSignature := nStoreSignatureValue;",
            "    bLoadStore := bStoreKept;"]
    for z in ZONES:
        out += zone_init(table, z)
    out += ["    bInitDone := TRUE;", "  END_IF;"]
    for z in ZONES:
        out += zone_call(table, z)
    out.append("END_PROGRAM")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    OUT.write_text(generate())
    BLOCK.write_text(zone_block(read_table())[0])
    print(f"wrote {OUT} and {BLOCK}")
