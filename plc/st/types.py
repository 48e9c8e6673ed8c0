"""IEC elementary and derived types with the C representation MatIEC gives them.

`ctype` names the C arithmetic class an operand has after C's integer promotion:
'i32', 'u32', 'i64', 'u64' for integers, 'f' (float, REAL), 'd' (double, LREAL and
untyped real literals), 'time', 'bool', 'str'.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(eq=False)
class Type:
    name: str  # upper-case IEC name, e.g. "INT", "ST_PT", "ARRAY"
    kind: str  # int real bool time enum struct array fb string anyint anyreal unknown
    bits: int = 0
    signed: bool = True
    bitstring: bool = False  # BYTE WORD DWORD LWORD

    # derived types
    members: list[str] = field(default_factory=list)  # enum members (upper) in order
    fields: dict[str, Type] = field(default_factory=dict)  # struct fields (lower-case names)
    field_inits: dict[str, object] = field(default_factory=dict)  # tree nodes / texts for defaults
    elem: Type | None = None  # array element type
    dims: list[tuple[int, int]] = field(default_factory=list)  # array bounds
    init: object = None  # alias/array type initializer (node or text)
    pou: object = None  # FB/ function POU object
    alias_of: Type | None = None

    @property
    def size(self) -> int:
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n

    @property
    def ctype(self) -> str:
        if self.kind in ("int", "enum"):
            if self.kind == "enum" or self.bits < 32:
                return "i32"
            return ("i" if self.signed else "u") + str(self.bits)
        if self.kind == "bool":
            return "i32"
        if self.kind == "real":
            return "f" if self.bits == 32 else "d"
        if self.kind == "anyreal":
            return "d"
        if self.kind == "anyint":
            return "i32"
        return self.kind

    def is_num(self) -> bool:
        return self.kind in ("int", "real", "anyint", "anyreal")

    def is_intlike(self) -> bool:
        return self.kind in ("int", "anyint")

    def is_real(self) -> bool:
        return self.kind in ("real", "anyreal")

    def __repr__(self) -> str:
        return f"Type({self.name})"


def _int(name: str, bits: int, signed: bool, bitstring: bool = False) -> Type:
    return Type(name, "int", bits, signed, bitstring)


ELEMENTARY: dict[str, Type] = {
    "BOOL": Type("BOOL", "bool", 1, False),
    "SINT": _int("SINT", 8, True),
    "INT": _int("INT", 16, True),
    "DINT": _int("DINT", 32, True),
    "LINT": _int("LINT", 64, True),
    "USINT": _int("USINT", 8, False),
    "UINT": _int("UINT", 16, False),
    "UDINT": _int("UDINT", 32, False),
    "ULINT": _int("ULINT", 64, False),
    "BYTE": _int("BYTE", 8, False, True),
    "WORD": _int("WORD", 16, False, True),
    "DWORD": _int("DWORD", 32, False, True),
    "LWORD": _int("LWORD", 64, False, True),
    "REAL": Type("REAL", "real", 32),
    "LREAL": Type("LREAL", "real", 64),
    "TIME": Type("TIME", "time", 64),
    "DATE": Type("DATE", "time", 64),
    "TIME_OF_DAY": Type("TIME_OF_DAY", "time", 64),
    "TOD": Type("TIME_OF_DAY", "time", 64),
    "DATE_AND_TIME": Type("DATE_AND_TIME", "time", 64),
    "DT": Type("DATE_AND_TIME", "time", 64),
    "STRING": Type("STRING", "string"),
}
ANY_INT = Type("ANY_INT", "anyint", 32)
ANY_REAL = Type("ANY_REAL", "anyreal", 64)
VOID = Type("VOID", "void")

BOOL = ELEMENTARY["BOOL"]
REAL = ELEMENTARY["REAL"]
LREAL = ELEMENTARY["LREAL"]
DINT = ELEMENTARY["DINT"]
LINT = ELEMENTARY["LINT"]
INT = ELEMENTARY["INT"]
TIME = ELEMENTARY["TIME"]
STRING = ELEMENTARY["STRING"]


UNKNOWN = "unknown"  # kind of a type named in no checked file (the checker's lenient index only)


def has_unknown(t: Type | None, seen: set[int] | None = None) -> bool:
    """Whether a type is, or is built from, an UNKNOWN type."""
    if t is None:
        return False
    seen = seen if seen is not None else set()
    if id(t) in seen:
        return False
    seen.add(id(t))
    if t.kind == UNKNOWN:
        return True
    parts = [*t.fields.values(), t.elem]
    if t.kind == "fb" and not isinstance(t.pou, str) and t.pou is not None:
        parts += [v.type for v in t.pou.vars.values()]
    return any(has_unknown(p, seen) for p in parts)


def wrap_expr(t: Type) -> str | None:
    """Name of the runtime helper that stores an integer into type t (None = none needed)."""
    if t.kind == "int":
        return f"_w{'s' if t.signed else 'u'}{t.bits}"
    if t.kind == "bool":
        return "bool"
    return None
