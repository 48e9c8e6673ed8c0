"""REAL rounding inside compiled scans (`scan_f32`) gives what C's float cast gives, as `f32` does:
nearest binary32, overflow to +-inf, NaN kept, subnormals and signed zero kept."""

from __future__ import annotations

import math
import random
import struct

from plc.st.rt import f32, scan_f32

FLT_MAX = struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0]
EDGES = [0.0, -0.0, 1.1, -1.1, 0.1, 1e-46, -1e-46, 1.4e-45, 7e-46, 1.1754942e-38, FLT_MAX,
         3.4028235e38, 3.40282356e38, 3.4028236e38, 1e39, -1e39, 1e300, -1e300, math.inf, -math.inf,
         2**24 + 1, -(2**31), 2**63 - 1]


def test_edges_round_as_c_does() -> None:
    rnd = scan_f32()
    for x in EDGES:
        assert rnd(x) == f32(x) and math.copysign(1.0, rnd(x)) == math.copysign(1.0, f32(x)), x
    assert rnd(1e39) == math.inf and rnd(-1e300) == -math.inf
    assert math.isnan(rnd(math.nan))


def test_random_doubles_round_alike() -> None:
    gen = random.Random(5)
    rnd = scan_f32()
    for _ in range(20000):
        x = gen.uniform(-1.0, 1.0) * 10.0 ** gen.randint(-45, 39)
        assert rnd(x) == f32(x), x


def test_each_application_rounds_through_its_own_slot() -> None:
    first, second = scan_f32(), scan_f32()
    assert first(1.1) == f32(1.1)
    assert second(2.5) == 2.5
    assert first.__defaults__[0] is not second.__defaults__[0]
