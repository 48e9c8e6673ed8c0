"""Names MatIEC (OpenPLC v3's iec2c, flags -f -l -p -r -R -a) treats specially.

Sources: IEC 61131-3 (2nd ed.) keyword table, MatIEC's lexer behaviour recorded in
../shared/reference/matiec-dialect.md (rows ident_st_keyword, ident_keyword_tod, ident_ref_as_name,
enum_keyword_member, ident_std_function) and the conformance README (standard FB names cannot name
variables).
All sets hold upper-case names; ST identifiers are case-insensitive.
"""

from __future__ import annotations

from plc.st.types import ELEMENTARY


def _names(kind: str, **attrs: bool) -> frozenset[str]:
    """Names of the soft-PLC's elementary types of one kind (one table for checker and compiler)."""
    return frozenset(
        name
        for name, t in ELEMENTARY.items()
        if t.kind == kind and all(getattr(t, a) == v for a, v in attrs.items())
    )


SIGNED_INT_TYPES = _names("int", bitstring=False, signed=True)
UNSIGNED_INT_TYPES = _names("int", bitstring=False, signed=False)
INT_TYPES = SIGNED_INT_TYPES | UNSIGNED_INT_TYPES
BIT_TYPES = _names("int", bitstring=True)
REAL_TYPES = _names("real")
TIME_TYPES = _names("time")
NUMERIC_TYPES = INT_TYPES | BIT_TYPES | REAL_TYPES
ELEMENTARY_TYPES = NUMERIC_TYPES | TIME_TYPES | frozenset({"BOOL", "STRING"})

# Pseudo-types of untyped literals (MatIEC types them by context, never as REAL from an integer).
ANY_INT = "ANY_INT"
ANY_REAL = "ANY_REAL"

GENERIC_TYPES = frozenset(
    {
        "ANY",
        "ANY_DERIVED",
        "ANY_ELEMENTARY",
        "ANY_MAGNITUDE",
        "ANY_NUM",
        "ANY_REAL",
        "ANY_INT",
        "ANY_BIT",
        "ANY_STRING",
        "ANY_DATE",
    }
)

# TwinCAT / IEC v3 types MatIEC does not know (rows ltime, wstring, union).
UNSUPPORTED_TYPES = {
    "LTIME": "LTIME is not supported by MatIEC (use TIME)",
    "WSTRING": "WSTRING is not supported by MatIEC/OpenPLC (use STRING)",
    "LDATE": "LDATE is not supported by MatIEC",
    "LTOD": "LTOD is not supported by MatIEC",
    "LDT": "LDT is not supported by MatIEC",
}

KEYWORDS = (
    frozenset(
        {
            # POU / block structure
            "ACTION",
            "END_ACTION",
            "CONFIGURATION",
            "END_CONFIGURATION",
            "FUNCTION",
            "END_FUNCTION",
            "FUNCTION_BLOCK",
            "END_FUNCTION_BLOCK",
            "PROGRAM",
            "END_PROGRAM",
            "RESOURCE",
            "END_RESOURCE",
            "TYPE",
            "END_TYPE",
            "STRUCT",
            "END_STRUCT",
            "VAR",
            "VAR_INPUT",
            "VAR_OUTPUT",
            "VAR_IN_OUT",
            "VAR_TEMP",
            "VAR_EXTERNAL",
            "VAR_GLOBAL",
            "VAR_ACCESS",
            "VAR_CONFIG",
            "END_VAR",
            "CONSTANT",
            "RETAIN",
            "NON_RETAIN",
            "AT",
            "TASK",
            "WITH",
            "ON",
            "SINGLE",
            "INTERVAL",
            "PRIORITY",
            "READ_ONLY",
            "READ_WRITE",
            "ARRAY",
            "OF",
            "R_EDGE",
            "F_EDGE",
            "EN",
            "ENO",
            # SFC
            "STEP",
            "END_STEP",
            "INITIAL_STEP",
            "TRANSITION",
            "END_TRANSITION",
            "FROM",
            # statements and operators
            "IF",
            "THEN",
            "ELSIF",
            "ELSE",
            "END_IF",
            "CASE",
            "END_CASE",
            "FOR",
            "TO",
            "BY",
            "DO",
            "END_FOR",
            "WHILE",
            "END_WHILE",
            "REPEAT",
            "UNTIL",
            "END_REPEAT",
            "EXIT",
            "CONTINUE",
            "RETURN",
            "AND",
            "OR",
            "XOR",
            "NOT",
            "MOD",
            "TRUE",
            "FALSE",
            # elementary type names (TOD / DT are the short forms MatIEC also reserves)
            "BOOL",
            "SINT",
            "INT",
            "DINT",
            "LINT",
            "USINT",
            "UINT",
            "UDINT",
            "ULINT",
            "REAL",
            "LREAL",
            "TIME",
            "DATE",
            "TIME_OF_DAY",
            "TOD",
            "DATE_AND_TIME",
            "DT",
            "STRING",
            "WSTRING",
            "BYTE",
            "WORD",
            "DWORD",
            "LWORD",
            "VOID",
        }
    )
    | GENERIC_TYPES
)

# Reserved because OpenPLC runs iec2c with -r / -R (REF_TO, REF(), NULL, DREF).
REF_RESERVED = frozenset({"REF", "REF_TO", "NULL", "DREF"})

# Function blocks of MatIEC's standard library (lib/ieclib.txt): their names are type names.
STANDARD_FBS = frozenset(
    {
        "TON",
        "TOF",
        "TP",
        "R_TRIG",
        "F_TRIG",
        "SR",
        "RS",
        "SEMA",
        "RTC",
        "CTU",
        "CTU_DINT",
        "CTU_LINT",
        "CTU_UDINT",
        "CTU_ULINT",
        "CTD",
        "CTD_DINT",
        "CTD_LINT",
        "CTD_UDINT",
        "CTD_ULINT",
        "CTUD",
        "CTUD_DINT",
        "CTUD_LINT",
        "CTUD_UDINT",
        "CTUD_ULINT",
        "PID",
        "RAMP",
        "HYSTERESIS",
        "INTEGRAL",
        "DERIVATIVE",
        # OpenPLC v3 adds these to its copy of the library (webserver/lib: communication_blocks.txt,
        # sm_cards.txt, SL-RP4.txt); checked with OpenPLC's iec2c: a variable Tcp_Send is refused.
        "TCP_CONNECT",
        "TCP_CLOSE",
        "TCP_SEND",
        "TCP_RECEIVE",
        "ROTARY_SWITCH",
        "SM_8RELAY",
        "SM_16RELAY",
        "SM_8DIN",
        "SM_16DIN",
        "SM_4REL4IN",
        "SM_8MOSFET",
        "SM_BAS",
        "SM_HOME",
        "SM_INDUSTRIAL",
        "SM_RTD",
        "SLM_INIT",
        "SLM_04THM_CONFIG",
        "SLM_ANALOG_IN_4",
        "SLM_ANALOG_IN_8",
        "SLM_ANALOG_OUT_4",
        "SLM_ANALOG_OUT_8",
        "SLM_DISCRETE_IN_8",
        "SLM_DISCRETE_IN_16",
        "SLM_DISCRETE_OUT_8",
        "SLM_DISCRETE_OUT_15",
        "SLM_DISCRETE_OUT_16",
        "SLM_TEMPERATURE_4",
    }
)

# Interface of the standard FBs whose members the checker types (others stay unknown).
_TIMER = {"IN": "BOOL", "PT": "TIME", "Q": "BOOL", "ET": "TIME"}
_EDGE = {"CLK": "BOOL", "Q": "BOOL"}


def _counter(kind: str, cv: str) -> dict[str, str]:
    members = {"R": "BOOL", "LD": "BOOL", "PV": cv, "CV": cv}
    if kind in ("CTU", "CTUD"):
        members["CU"] = "BOOL"
    if kind in ("CTD", "CTUD"):
        members["CD"] = "BOOL"
    if kind == "CTUD":
        members.update({"QU": "BOOL", "QD": "BOOL"})
    else:
        members["Q"] = "BOOL"
    return members


STANDARD_FB_MEMBERS: dict[str, dict[str, str]] = {
    "TON": _TIMER,
    "TOF": _TIMER,
    "TP": _TIMER,
    "R_TRIG": _EDGE,
    "F_TRIG": _EDGE,
    "SR": {"S1": "BOOL", "R": "BOOL", "Q1": "BOOL"},
    "RS": {"S": "BOOL", "R1": "BOOL", "Q1": "BOOL"},
}
for _kind in ("CTU", "CTD", "CTUD"):
    STANDARD_FB_MEMBERS[_kind] = _counter(_kind, "INT")
    for _suffix in ("DINT", "LINT", "UDINT", "ULINT"):
        STANDARD_FB_MEMBERS[f"{_kind}_{_suffix}"] = _counter(_kind, _suffix)

# Standard functions whose result has the type of their (first) numeric argument.
SAME_TYPE_FUNCTIONS = frozenset(
    {
        "ABS",
        "SQRT",
        "LN",
        "LOG",
        "EXP",
        "SIN",
        "COS",
        "TAN",
        "ASIN",
        "ACOS",
        "ATAN",
        "EXPT",
        "SHL",
        "SHR",
        "ROL",
        "ROR",
        "MOVE",
    }
)
# Standard selection functions: result = common type of these argument positions (None = all).
SELECTION_FUNCTIONS: dict[str, slice] = {
    "MIN": slice(0, None),
    "MAX": slice(0, None),
    "LIMIT": slice(0, None),
    "SEL": slice(1, None),
    "MUX": slice(1, None),
}
FIXED_RESULT_FUNCTIONS = {
    "LEN": "INT",
    "CONCAT": "STRING",
    "LEFT": "STRING",
    "RIGHT": "STRING",
    "MID": "STRING",
    "INSERT": "STRING",
    "DELETE": "STRING",
    "REPLACE": "STRING",
    "FIND": "INT",
}

# TwinCAT / IEC v3 generic conversions (row generic_to_conv).
GENERIC_CONVERSIONS = frozenset({f"TO_{t}" for t in ELEMENTARY_TYPES | {"WSTRING", "LTIME"}})
# TwinCAT address / size operators (row adr_sizeof, pointer_to_twincat).
TWINCAT_OPERATORS = frozenset({"ADR", "ADRINST", "SIZEOF", "BITADR", "__NEW", "__DELETE", "__QUERYINTERFACE"})

# Functions of MatIEC's standard library (lib/ieclib.txt, IEC 61131-3 2nd ed. tables 22-36): once the
# library is loaded their names are function-name tokens, so iec2c refuses them as variable names
# (checked with iec2c: a variable nE, eq, max, len, trunc or int_to_real fails with "invalid located
# variable declaration"; struct members named so are accepted). Besides the generic names, MatIEC
# declares typed variants <NAME>_<TYPE> (ADD_REAL, MUX_INT_REAL, SUB_DT_TIME) and the conversions.
STANDARD_FUNCTIONS = frozenset(
    {
        "ABS", "SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN",
        "ADD", "SUB", "MUL", "DIV", "MOD", "EXPT", "MOVE", "TRUNC", "DIVTIME", "MULTIME",
        "SHL", "SHR", "ROL", "ROR", "AND", "OR", "XOR", "NOT",
        "SEL", "MAX", "MIN", "LIMIT", "MUX",
        "GT", "GE", "EQ", "LE", "LT", "NE",
        "LEN", "LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE", "REPLACE", "FIND",
    }
)  # fmt: skip
# Generic functions MatIEC also declares once per argument type (ADD_REAL, EQ_TIME, MUX_INT_REAL).
_TYPED_VARIANT_FUNCTIONS = STANDARD_FUNCTIONS - {
    "EXPT", "TRUNC", "SHL", "SHR", "ROL", "ROR", "LEN", "LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE",
    "REPLACE", "FIND",
}  # fmt: skip
_TIME_FUNCTIONS = frozenset(
    {"ADD_TOD_TIME", "ADD_DT_TIME", "SUB_DATE_DATE", "SUB_TOD_TIME", "SUB_TOD_TOD", "SUB_DT_TIME",
     "SUB_DT_DT", "CONCAT_DATE_TOD"}
)  # fmt: skip
_SHORT_TYPE_NAMES = ELEMENTARY_TYPES - {"TIME_OF_DAY", "DATE_AND_TIME"}
_BCD_BITS = ("BYTE", "WORD", "DWORD", "LWORD")
_CONVERSION_ENDS = (
    ELEMENTARY_TYPES | {f"{b}_BCD" for b in _BCD_BITS} | {f"BCD_{b}" for b in _BCD_BITS} | {"BCD"}
)


def is_standard_function(name: str) -> bool:
    """Whether `name` (any case) is a function of MatIEC's standard library (a small superset of it)."""
    upper = name.upper()
    if upper in STANDARD_FUNCTIONS or upper in _TIME_FUNCTIONS:
        return True
    source, sep, target = upper.partition("_TO_")
    if sep:
        return source in _CONVERSION_ENDS and target in _CONVERSION_ENDS
    base, _, suffix = upper.partition("_")
    if base not in _TYPED_VARIANT_FUNCTIONS or not suffix:
        return False
    if base == "MUX":
        selector, _, value_type = suffix.partition("_")
        return selector in INT_TYPES and value_type in _SHORT_TYPE_NAMES
    return suffix in _SHORT_TYPE_NAMES


def is_reserved(name: str) -> str | None:
    """Why `name` cannot be a user identifier in MatIEC, or None."""
    upper = name.upper()
    if upper in REF_RESERVED:
        return f"'{name}' is reserved (OpenPLC runs iec2c with -r/-R: REF, REF_TO, NULL)"
    if upper in KEYWORDS:
        return f"'{name}' is a keyword in MatIEC and cannot be used as an identifier"
    if upper in STANDARD_FBS:
        return f"'{name}' is the name of a standard function block and cannot be used as an identifier"
    return None


def naming_problem(name: str) -> str | None:
    """IEC 61131-3 underscore rules (rows ident_double_underscore, ident_trailing_underscore)."""
    if "__" in name:
        return f"identifier '{name}' contains a double underscore, which MatIEC rejects"
    if name.endswith("_"):
        return f"identifier '{name}' ends with an underscore, which MatIEC rejects"
    return None
