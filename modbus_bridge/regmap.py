"""The Modbus register map, derived from the application's located variables (one source of truth).

`load_register_map()` parses `plc/app/*.st` with the project's ST parser and maps every located
variable of the PROGRAM(s) to OpenPLC v3's Modbus tables (reference/openplc.md):
%IX a.b -> discrete input 8a+b, %QX a.b -> coil 8a+b, %IW n -> input register n, %QW n -> holding n,
%MW n -> holding 1024+n, %MD n -> holding 2048+2n (2 words, high word first), %ML n -> holding 4096+4n.
The comment that follows a declaration on the same line is its description.
`markdown()` renders docs/register-map.md (`thermost regmap --markdown`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

APP_DIR = Path(__file__).resolve().parents[1] / "plc" / "app"

COIL, DISCRETE, HOLDING, INPUT = "coil", "discrete input", "holding register", "input register"
MW_BASE, MD_BASE, ML_BASE = 1024, 2048, 4096
WORDS_PER_SIZE = {"X": 0, "B": 1, "W": 1, "D": 2, "L": 4}
TYPE_SIZES = {
    "BOOL": "X",
    "SINT": "B",
    "USINT": "B",
    "BYTE": "B",
    "INT": "W",
    "UINT": "W",
    "WORD": "W",
    "DINT": "D",
    "UDINT": "D",
    "DWORD": "D",
    "REAL": "D",
    "TIME": "D",
    "LINT": "L",
    "ULINT": "L",
    "LWORD": "L",
    "LREAL": "L",
}
_LOCATION = re.compile(r"^%([IQM])([XBWDL]?)(\d+)(?:\.(\d+))?$", re.IGNORECASE)


class RegisterMapError(ValueError):
    pass


OWNERS = ("plc", "client", "command", "input")
_META = re.compile(r"\{([^{}]*)\}\s*$")
_ZONE = re.compile(r"Zone(\d+)$")


@dataclass(frozen=True)
class TagMeta:
    """A register's metadata, from the `{key=value; ...}` tail of its declaration comment.

    owner: `plc` (status, rewritten every scan), `client` (parameter; the PLC validates it and the
    register shows the value in use), `command` (the PLC resets it after acting), `input` (process
    input written by the plant or harness)."""

    unit: str = ""
    min: float | None = None
    max: float | None = None
    default: float | None = None
    decimals: int = 0
    enum: dict[int, str] = field(default_factory=dict)
    owner: str = "client"
    group: str = ""
    zone: int | None = None

    @property
    def writable_by_client(self) -> bool:
        return self.owner in ("client", "command", "input")


def parse_meta(comment: str, name: str, where: str) -> tuple[str, TagMeta]:
    """(plain description, metadata) of one declaration comment."""
    zone_match = _ZONE.search(name)
    zone = int(zone_match.group(1)) if zone_match else None
    m = _META.search(comment)
    if not m:
        return comment, TagMeta(zone=zone)
    values: dict[str, object] = {"zone": zone}
    for item in filter(None, (part.strip() for part in m.group(1).split(";"))):
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        try:
            if not sep:
                raise ValueError("expected key=value")
            if key in ("min", "max", "default"):
                values[key] = float(value)
            elif key == "dec":
                values["decimals"] = int(value)
            elif key == "enum":
                values["enum"] = {int(k): t for k, _, t in (e.partition(":") for e in value.split(","))}
            elif key == "owner":
                if value not in OWNERS:
                    raise ValueError(f"owner must be one of {', '.join(OWNERS)}")
                values["owner"] = value
            elif key in ("unit", "group"):
                values[key] = value
            else:
                raise ValueError("unknown key")
        except ValueError as exc:
            raise RegisterMapError(f"{where}: {name}: bad metadata {item!r}: {exc}") from None
    return comment[: m.start()].rstrip(), TagMeta(**values)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Tag:
    name: str
    program: str
    location: str
    area: str  # I, Q, M
    size: str  # X, B, W, D, L
    index: int
    bit: int | None
    iec_type: str
    comment: str
    table: str  # COIL, DISCRETE, HOLDING, INPUT
    address: int  # 0-based Modbus address in that table
    words: int  # registers (0 for bits)
    writable: bool  # a Modbus client may write it
    source: str  # file:line
    meta: TagMeta = field(default_factory=TagMeta)

    @property
    def is_bit(self) -> bool:
        return self.size == "X"


def modbus_address(area: str, size: str, index: int, bit: int | None) -> tuple[str, int, bool] | None:
    """(table, address, client-writable) for an IEC location as OpenPLC v3 maps it; None if unmapped."""
    if size == "X":
        if bit is None or not 0 <= bit <= 7:
            return None
        if area == "I":
            return DISCRETE, 8 * index + bit, False
        if area == "Q":
            return COIL, 8 * index + bit, True
        return None
    if area == "I" and size == "W":
        return INPUT, index, False
    if area == "Q" and size == "W":
        return HOLDING, index, True
    if area == "M" and size == "W":
        return HOLDING, MW_BASE + index, True
    if area == "M" and size == "D":
        return HOLDING, MD_BASE + 2 * index, True
    if area == "M" and size == "L":
        return HOLDING, ML_BASE + 4 * index, True
    return None


@dataclass
class RegisterMap:
    tags: dict[str, Tag]
    sources: list[str]

    def __getitem__(self, name: str) -> Tag:
        try:
            return self.tags[name]
        except KeyError:
            raise RegisterMapError(
                f"tag '{name}' is not in the register map (located variables of "
                f"{', '.join(self.sources) or 'the application'})"
            ) from None

    def __contains__(self, name: str) -> bool:
        return name in self.tags

    def find(self, pattern: str) -> list[Tag]:
        rx = re.compile(pattern)
        return [t for t in self.tags.values() if rx.fullmatch(t.name)]


def _comment_after(node, text_bytes: bytes) -> str:
    sib = node.next_sibling
    if sib is not None and sib.type == "comment" and sib.start_point[0] == node.end_point[0]:
        body = sib.text.decode("utf-8", "replace")
        return " ".join(body.removeprefix("(*").removesuffix("*)").split())
    return ""


def parse_located(text: str, filename: str) -> list[Tag]:
    """Located variables of every PROGRAM in one ST source."""
    from plc.st.parser import parse_source

    parsed = parse_source(text, filename)
    errors = parsed.syntax_errors()
    if errors:
        raise RegisterMapError(f"{errors[0]}")
    tags: list[Tag] = []

    def walk(node, program: str) -> None:
        if node.type == "program_declaration":
            ident = next((c for c in node.children if c.type == "identifier"), None)
            program = ident.text.decode() if ident is not None else ""
        if node.type == "variable_declaration" and program:
            addr = next((c for c in node.children if c.type == "direct_address"), None)
            if addr is not None:
                tags.append(_make_tag(node, addr, program, filename, parsed.src))
            return
        for child in node.children:
            walk(child, program)

    walk(parsed.tree.root_node, "")
    return tags


def _make_tag(node, addr, program: str, filename: str, src: bytes) -> Tag:
    names = [c.text.decode() for c in node.children if c.type == "identifier"]
    type_node = next((c for c in node.children if c.type.endswith("type") or c.type == "type_name"), None)
    iec_type = type_node.text.decode().upper() if type_node is not None else ""
    location = addr.text.decode()
    line = node.start_point[0] + 1
    m = _LOCATION.match(location)
    if not m or len(names) != 1:
        raise RegisterMapError(f"{filename}:{line}: cannot map located variable {location}")
    area, size, index, bit = m.group(1).upper(), (m.group(2) or "X").upper(), int(m.group(3)), m.group(4)
    expected = TYPE_SIZES.get(iec_type)
    if expected is not None and expected != size:
        raise RegisterMapError(f"{filename}:{line}: {names[0]} : {iec_type} cannot sit at {location}")
    mapped = modbus_address(area, size, index, int(bit) if bit is not None else None)
    if mapped is None:
        raise RegisterMapError(f"{filename}:{line}: {location} has no Modbus address in OpenPLC's map")
    table, address, writable = mapped
    description, meta = parse_meta(_comment_after(node, src), names[0], f"{Path(filename).name}:{line}")
    return Tag(
        name=names[0],
        program=program,
        location=location.upper(),
        area=area,
        size=size,
        index=index,
        bit=int(bit) if bit is not None else None,
        iec_type=iec_type,
        comment=description,
        table=table,
        address=address,
        words=WORDS_PER_SIZE[size],
        writable=writable,
        source=f"{Path(filename).name}:{line}",
        meta=meta,
    )


def load_register_map(
    app_dir: Path | None = None, sources: list[tuple[str, str]] | None = None
) -> RegisterMap:
    """Register map of the application (default plc/app/*.st) or of explicit (filename, text) sources."""
    if sources is None:
        directory = app_dir or APP_DIR
        files = sorted(directory.glob("*.st"))
        if not files:
            raise RegisterMapError(f"no application .st files in {directory}")
        sources = [(str(f), f.read_text(encoding="utf-8")) for f in files]
    tags: dict[str, Tag] = {}
    used: dict[tuple[str, int], str] = {}
    for filename, text in sources:
        for tag in parse_located(text, filename):
            if tag.name in tags:
                raise RegisterMapError(f"{tag.source}: located variable {tag.name} declared twice")
            for k in range(max(tag.words, 1)):
                slot = (tag.table, tag.address + k)
                if slot in used:
                    raise RegisterMapError(
                        f"{tag.source}: {tag.name} at {tag.location} overlaps {used[slot]}"
                    )
                used[slot] = tag.name
            tags[tag.name] = tag
    return RegisterMap(tags=tags, sources=[Path(f).name for f, _ in sources])


def markdown(regmap: RegisterMap) -> str:
    """docs/register-map.md: one table per Modbus table, ordered by address."""
    lines = [
        "# Register map (generated)",
        "",
        "Generated by `thermost regmap --markdown -o docs/register-map.md` from the located variables of "
        f"{', '.join(f'`plc/app/{s}`' for s in regmap.sources)}; do not edit by hand "
        "(a test checks this file is up to date).",
        "",
        "Addresses are 0-based Modbus addresses as OpenPLC v3 maps them (`reference/openplc.md`): "
        "32-bit values (%MD) take two holding registers, high word first; REAL is IEEE 754 binary32. "
        "BOOLs at %QX are coils, at %IX discrete inputs (read only). %IW are input registers (read only). "
        "Write a 32-bit value in one request (FC16), never word by word.",
        "",
        "Owner: **plc** = status the PLC rewrites every scan (a client write is overwritten: read only); "
        "**client** = a parameter a client writes; the PLC checks it, the register shows the value in use; "
        "**command** = the PLC resets it after acting on it; **input** = process input written by the plant "
        "or harness. Range is what the PLC accepts; default is per zone (zone 1 / zone 2 where they differ).",
        "",
    ]
    order = (HOLDING, COIL, INPUT, DISCRETE)
    for table in order:
        tags = sorted(
            (t for t in regmap.tags.values() if t.table == table), key=lambda t: (t.address, t.name)
        )
        if not tags:
            continue
        lines += [
            f"## {table}s",
            "",
            "| address | words | location | tag | type | owner | unit | range | default | description |",
            "|---:|---:|---|---|---|---|---|---|---|---|",
        ]
        for t in tags:
            m = t.meta
            owner = m.owner if t.writable else f"{m.owner} (R)"
            rng = "" if m.min is None and m.max is None else f"{_num(m.min)} .. {_num(m.max)}"
            desc = t.comment
            if m.enum:
                desc += " (" + ", ".join(f"{k} {v}" for k, v in sorted(m.enum.items())) + ")"
            desc = desc.replace("|", "\\|")
            lines.append(
                f"| {t.address} | {t.words or '-'} | `{t.location}` | `{t.name}` | {t.iec_type} | {owner} | "
                f"{m.unit} | {rng} | {_num(m.default) if m.default is not None else ''} | {desc} |"
            )
        lines.append("")
    return "\n".join(lines)


def _num(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:g}"
