"""A small stand-in for `plc.st.compiler.Application` (same attributes) for runtime tests.

Program (per scan): cnt := cnt + 1; out_real := in_real * 2.0; out_int := in_int + 1;
q_copy := ix_in; divisor = 0 -> integer division fault; index > 3 -> array index fault.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from plc.st.app import LocatedVar
from plc.st.errors import PlcRuntimeError
from plc.st.rt import f32

INTERVAL_NS = 10_000_000


@dataclass
class FakeApplication:
    interval_ns: int = INTERVAL_NS
    time_ns: int = 0
    fault: PlcRuntimeError | None = None
    values: dict[str, Any] = field(default_factory=dict)
    located: list[LocatedVar] = field(default_factory=list)

    def __post_init__(self) -> None:
        layout = [
            # name, location, area, size, index, bit, type, initial
            ("cnt", "%MD0", "M", "D", 0, None, "DINT", 0),
            ("in_real", "%MD1", "M", "D", 1, None, "REAL", 0.0),
            ("out_real", "%MD2", "M", "D", 2, None, "REAL", 0.0),
            ("in_int", "%MW0", "M", "W", 0, None, "INT", 0),
            ("out_int", "%MW1", "M", "W", 1, None, "INT", 0),
            ("divisor", "%MW2", "M", "W", 2, None, "INT", 1),
            ("index", "%MW3", "M", "W", 3, None, "INT", 0),
            ("qw_word", "%QW0", "Q", "W", 0, None, "WORD", 0xBEEF),
            ("iw_in", "%IW5", "I", "W", 5, None, "INT", -2),
            ("ix_in", "%IX0.3", "I", "X", 0, 3, "BOOL", True),
            ("q_copy", "%QX1.2", "Q", "X", 1, 2, "BOOL", False),
            ("big", "%ML2", "M", "L", 2, None, "LINT", -5),
            ("lr", "%ML3", "M", "L", 3, None, "LREAL", 2.5),
            ("ud", "%MD5", "M", "D", 5, None, "UDINT", 4000000000),
            ("byte_in", "%IB0", "I", "B", 0, None, "BYTE", 0),
        ]
        for name, location, area, size, index, bit, iec_type, initial in layout:
            self.values[name] = initial
            self.located.append(LocatedVar(
                name, "inst0", location, area, size, index, bit, iec_type,
                (lambda n=name: self.values[n]), (lambda v, n=name: self.values.__setitem__(n, v)),
            ))

    def scan(self) -> None:
        if self.fault is not None:
            return
        v = self.values
        v["cnt"] = v["cnt"] + 1
        v["out_real"] = f32(v["in_real"] * 2.0)
        v["out_int"] = ((v["in_int"] + 1 + 0x8000) & 0xFFFF) - 0x8000
        v["q_copy"] = v["ix_in"]
        try:
            if v["divisor"] == 0:
                raise PlcRuntimeError("divzero", "integer division by zero in P_Fake line 7")
            if not 0 <= v["index"] <= 3:
                raise PlcRuntimeError("index", f"array index {v['index']} outside 0..3 in P_Fake line 9")
        except PlcRuntimeError as exc:
            self.fault = exc
            raise
        self.time_ns += self.interval_ns

    def reset_fault(self) -> None:
        self.fault = None

    def get(self, path: str) -> Any:
        return self.values[path.split(".")[-1]]

    def set(self, path: str, value: Any) -> None:
        self.values[path.split(".")[-1]] = value


def test_fake_application_counts_scans_and_time():
    app = FakeApplication()
    app.scan()
    app.scan()
    assert app.values["cnt"] == 2
    assert app.time_ns == 2 * INTERVAL_NS
