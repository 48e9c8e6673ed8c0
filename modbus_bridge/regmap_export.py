"""`thermost regmap --format csv|json|fuxa|node-red`: the register map with its metadata for other tools.

- csv / json: every column a panel needs (addresses 0- and 1-based, function codes, data type and word
  order, access, owner, unit, range, default, decimals, enum and alarm-bit texts, HMI level, poll class).
- fuxa: FUXA's device/tag CSV (`@header` lines, `D@` device row, `T@` tag rows, `~` for a comma inside a
  value); addresses 1-based (FUXA sends address - 1), Float32/Int32/UInt32 high word first.
- node-red: a flow for node-red-contrib-modbus: one reader per contiguous block of the zone registers and
  a function node that decodes them (big-endian float32 / int32 / int16, coils as booleans).
Everything comes from `load_register_map()` (the application's located variables and their metadata).
"""

from __future__ import annotations

import csv
import io
import json
import re
from dataclasses import dataclass

from .alarm_texts import alarm_texts
from .client import plan_reads
from .regmap import COIL, DISCRETE, HOLDING, INPUT, RegisterMap, Tag

FORMATS = ("csv", "json", "fuxa", "node-red")
FC_READ = {COIL: 1, DISCRETE: 2, HOLDING: 3, INPUT: 4}
FC_WRITE = {COIL: "5/15", HOLDING: "6/16"}
FUXA_TABLE = {COIL: "000000", DISCRETE: "100000", INPUT: "300000", HOLDING: "400000"}
DATA_TYPE = {"REAL": "Float32", "LREAL": "Float64", "DINT": "Int32", "UDINT": "UInt32", "DWORD": "UInt32",
             "TIME": "Int32", "INT": "Int16", "UINT": "UInt16", "WORD": "UInt16", "SINT": "Int16",
             "USINT": "UInt16", "BYTE": "UInt16", "BOOL": "Bool", "LINT": "Int64"}
# groups the operator level may write (the rest of the client registers need the engineer level)
OPERATOR_GROUPS = ("setpoint", "mode")
OPERATOR_TAGS = re.compile(r"bAckZone\d+$")
FAST_GROUPS = ("process", "status", "setpoint", "mode", "alarms")
COLUMNS = ("tag", "zone", "group", "location", "table", "address", "address_1based", "fc_read", "fc_write",
           "words", "iec_type", "data_type", "word_order", "access", "owner", "unit", "min", "max", "default",
           "decimals", "enum", "alarm_bits", "hmi_level", "poll_class", "description")
DEFAULT_POLL_MS = 500


@dataclass
class ExportOptions:
    host: str = "127.0.0.1"
    port: int = 5020
    unit_id: int = 1
    poll_ms: int = DEFAULT_POLL_MS


def _meta(tag: Tag):
    return getattr(tag, "meta", None)


def access_of(tag: Tag) -> str:
    owner = getattr(_meta(tag), "owner", "client" if tag.writable else "plc")
    if not tag.writable or owner == "plc":
        return "read"  # a status register: a client write is overwritten every scan
    if owner == "command":
        return "self-resetting command"
    return "read-write"


def hmi_level(tag: Tag) -> str:
    m = _meta(tag)
    if access_of(tag) == "read" or getattr(m, "owner", "") == "input":
        return "none"
    if getattr(m, "group", "") in OPERATOR_GROUPS or OPERATOR_TAGS.match(tag.name):
        return "operator"
    return "engineer"


def rows(regmap: RegisterMap) -> list[dict]:
    bits = alarm_texts()
    out = []
    for t in sorted(regmap.tags.values(), key=lambda t: (t.table, t.address)):
        m = _meta(t)
        enum = getattr(m, "enum", {}) or {}
        is_alarm_word = t.name.startswith("dwAlarm") and getattr(m, "group", "") in ("status", "alarms", "")
        out.append({
            "tag": t.name,
            "zone": getattr(m, "zone", None),
            "group": getattr(m, "group", ""),
            "location": t.location,
            "table": t.table,
            "address": t.address,
            "address_1based": t.address + 1,
            "fc_read": FC_READ[t.table],
            "fc_write": FC_WRITE.get(t.table, "") if t.writable else "",
            "words": t.words,
            "iec_type": t.iec_type,
            "data_type": DATA_TYPE.get(t.iec_type, t.iec_type),
            "word_order": "high word first" if t.words > 1 else "",
            "access": access_of(t),
            "owner": getattr(m, "owner", ""),
            "unit": getattr(m, "unit", ""),
            "min": getattr(m, "min", None),
            "max": getattr(m, "max", None),
            "default": getattr(m, "default", None),
            "decimals": getattr(m, "decimals", None),
            "enum": "; ".join(f"{k}={v}" for k, v in sorted(enum.items())),
            "alarm_bits": "; ".join(f"{b}={txt}" for b, txt in sorted(bits.items())) if is_alarm_word else "",
            "hmi_level": hmi_level(t),
            "poll_class": "fast" if getattr(m, "group", "") in FAST_GROUPS else "slow",
            "description": t.comment,
        })
    return out


def to_csv(regmap: RegisterMap) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows(regmap):
        w.writerow({k: "" if v is None else v for k, v in r.items()})
    return buf.getvalue()


def to_json(regmap: RegisterMap) -> str:
    return json.dumps({"word_order": "big-endian words, high word first (OpenPLC)", "tags": rows(regmap)},
                      indent=1) + "\n"


def _fuxa_cell(value: object) -> str:
    text = "" if value is None else str(value)
    return text.replace(",", "~").replace("\n", " ")


def _num(value: float | None) -> str:
    return "" if value is None else f"{value:g}"


def to_fuxa(regmap: RegisterMap, opts: ExportOptions) -> str:
    dev_id = "d_thermost"
    lines = [
        "# ThermoST register map for FUXA (Editor > Connections > import devices from CSV)",
        "# addresses are 1-based (FUXA sends address - 1); Float32/Int32/UInt32: high word first",
        "@header,id,name,enabled,type,polling,property.address,property.port,property.slaveid",
        "D@," + ",".join(_fuxa_cell(v) for v in (dev_id, "ThermoST", "true", "ModbusTCP", opts.poll_ms,
                                                  opts.host, opts.port, opts.unit_id)),
        "",
        "@header,deviceId,id,name,label,type,memaddress,address,divisor,init,format,description,daq.enabled,"
        "daq.interval",
    ]
    for r in rows(regmap):
        if r["table"] not in FUXA_TABLE:
            continue
        rng = "" if r["min"] is None and r["max"] is None else f"{_num(r['min'])}..{_num(r['max'])}"
        extra = " ".join(x for x in (rng, r["unit"]) if x)
        label = f"{r['description']}{f' [{extra}]' if extra else ''} ({r['access']})"
        lines.append("T@," + ",".join(_fuxa_cell(v) for v in (
            dev_id, f"t_{r['tag']}", r["tag"], label, r["data_type"], FUXA_TABLE[r["table"]],
            r["address_1based"], 1, "", r["decimals"] if r["decimals"] is not None else "",
            f"{r['location']}; owner {r['owner']}; HMI level {r['hmi_level']}", "false", 60)))
    return "\n".join(lines) + "\n"


_DECODERS = {
    "REAL": "f32", "DINT": "i32", "TIME": "i32", "UDINT": "u32", "DWORD": "u32",
    "INT": "i16", "SINT": "i16", "UINT": "u16", "WORD": "u16", "USINT": "u16", "BYTE": "u16",
}
DECODE_JS = (
    "const w = msg.payload;\n"
    "const buf = (i) => { const b = Buffer.alloc(4); b.writeUInt16BE(w[i] & 0xffff, 0); "
    "b.writeUInt16BE(w[i + 1] & 0xffff, 2); return b; };\n"
    "const f32 = (i) => buf(i).readFloatBE(0);\n"
    "const i32 = (i) => buf(i).readInt32BE(0);\n"
    "const u32 = (i) => buf(i).readUInt32BE(0);\n"
    "const i16 = (i) => ((w[i] & 0xffff) << 16) >> 16;\n"
    "const u16 = (i) => w[i] & 0xffff;\n"
    "const bit = (i) => Boolean(w[i]);\n"
)


def node_red_decoder(span_tags: list[Tag], start: int) -> str:
    """JavaScript of the function node that turns one block's words (or bits) into {tag: value}."""
    body = [DECODE_JS, "const out = {};"]
    for t in span_tags:
        fn = "bit" if t.is_bit else _DECODERS.get(t.iec_type)
        if fn is None:
            continue
        body.append(f"out[{json.dumps(t.name)}] = {fn}({t.address - start});")
    body.append("msg.payload = out;\nreturn msg;")
    return "\n".join(body)


def to_node_red(regmap: RegisterMap, opts: ExportOptions) -> str:
    zone_tags = [t for t in regmap.tags.values()
                 if getattr(_meta(t), "zone", None) is not None and t.table in (HOLDING, COIL)]
    tab, client = "thermost_tab", "thermost_client"
    nodes: list[dict] = [
        {"id": tab, "type": "tab", "label": "ThermoST zones", "info": "generated by thermost regmap"},
        {"id": client, "type": "modbus-client", "name": f"ThermoST {opts.host}:{opts.port}",
         "clienttype": "tcp", "bufferCommands": True, "stateLogEnabled": False, "queueLogEnabled": False,
         "failureLogEnabled": True, "tcpHost": opts.host, "tcpPort": str(opts.port), "tcpType": "DEFAULT",
         "unit_id": str(opts.unit_id), "commandDelay": "1", "clientTimeout": "1000",
         "reconnectOnTimeout": True, "reconnectTimeout": "2000", "parallelUnitIdsAllowed": False},
    ]
    debug = "thermost_debug"
    for k, span in enumerate(plan_reads(zone_tags)):
        reader, fn = f"thermost_read_{k}", f"thermost_decode_{k}"
        kind = "HoldingRegister" if span.table == HOLDING else "Coil"
        nodes.append({
            "id": reader, "z": tab, "type": "modbus-read",
            "name": f"{span.table}s {span.start}..{span.start + span.count - 1}", "topic": "",
            "showStatusActivities": False, "logIOActivities": False, "showErrors": True, "unitid": "",
            "dataType": kind, "adr": str(span.start), "quantity": str(span.count), "rate": str(opts.poll_ms),
            "rateUnit": "ms", "delayOnStart": False, "startDelayTime": "", "server": client,
            "useIOFile": False, "ioFile": "", "useIOForPayload": False, "emptyMsgOnFail": False,
            "x": 180, "y": 60 + 60 * k, "wires": [[fn], []]})
        nodes.append({
            "id": fn, "z": tab, "type": "function", "name": f"decode {len(span.tags)} tags",
            "func": node_red_decoder(span.tags, span.start), "outputs": 1, "noerr": 0,
            "x": 420, "y": 60 + 60 * k, "wires": [[debug]]})
    nodes.append({"id": debug, "z": tab, "type": "debug", "name": "zone values", "active": True,
                  "complete": "payload", "x": 640, "y": 60, "wires": []})
    return json.dumps(nodes, indent=1) + "\n"


def export(regmap: RegisterMap, fmt: str, opts: ExportOptions | None = None) -> str:
    opts = opts or ExportOptions()
    if fmt == "csv":
        return to_csv(regmap)
    if fmt == "json":
        return to_json(regmap)
    if fmt == "fuxa":
        return to_fuxa(regmap, opts)
    if fmt == "node-red":
        return to_node_red(regmap, opts)
    raise ValueError(f"unknown format {fmt!r} (one of {', '.join(FORMATS)})")


def main_regmap_export(args) -> int:
    """`thermost regmap` with --format; text and --markdown stay with the original handler."""
    import sys
    from pathlib import Path

    from plc.cli import UserError

    from .regmap import RegisterMapError, load_register_map
    from .runner import parse_host_port

    if not getattr(args, "format", None):
        from .cli import main_regmap

        return main_regmap(args)
    if args.markdown:
        raise UserError("--markdown and --format exclude each other")
    try:
        host, port = parse_host_port(args.plc)
        text = export(load_register_map(), args.format, ExportOptions(host=host, port=port))
    except (RegisterMapError, ValueError) as exc:
        raise UserError(str(exc)) from None
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0
