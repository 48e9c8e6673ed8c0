"""Runtime support for compiled ST: MatIEC's C semantics in Python.

Integers wrap like the C types MatIEC emits, REAL is IEEE binary32 after every operation
(`f32`), LREAL and untyped real literals are binary64, TIME is an integer count of
nanoseconds whose arithmetic mirrors MatIEC's (tv_sec, tv_nsec) helpers.
"""

from __future__ import annotations

import math
import struct
from array import array
from collections.abc import Callable
from fractions import Fraction

from plc.st.errors import PlcRuntimeError

_F32 = struct.Struct("<f")
_pack, _unpack = _F32.pack, _F32.unpack
INF = math.inf
NAN = math.nan
NS = 1_000_000_000


def f32(x: float) -> float:
    """Round a binary64 value to binary32 (C's (float) cast, overflow to +-inf)."""
    try:
        return _unpack(_pack(x))[0]
    except OverflowError:
        return INF if x > 0 else -INF


def scan_f32() -> Callable[[float], float]:
    """`f32` for one application's compiled code: rounds through a binary32 slot of its own (C's
    float cast, overflow to +-inf as C gives it), about half the cost of a pack and unpack. The slot
    is shared by every call of that application, so it must not run in two threads at once; its scans
    never do (the engine scans under a lock), and everything else uses `f32`."""
    slot = array("f", (0.0,))

    def f32_in_scan(x: float, _slot=slot) -> float:
        _slot[0] = x
        return _slot[0]

    return f32_in_scan


def ws8(x: int) -> int:
    return ((x + 0x80) & 0xFF) - 0x80


def ws16(x: int) -> int:
    return ((x + 0x8000) & 0xFFFF) - 0x8000


def ws32(x: int) -> int:
    return ((x + 0x80000000) & 0xFFFFFFFF) - 0x80000000


def ws64(x: int) -> int:
    return ((x + 0x8000000000000000) & 0xFFFFFFFFFFFFFFFF) - 0x8000000000000000


def wu8(x: int) -> int:
    return x & 0xFF


def wu16(x: int) -> int:
    return x & 0xFFFF


def wu32(x: int) -> int:
    return x & 0xFFFFFFFF


def wu64(x: int) -> int:
    return x & 0xFFFFFFFFFFFFFFFF


WRAP = {
    (8, True): ws8,
    (16, True): ws16,
    (32, True): ws32,
    (64, True): ws64,
    (8, False): wu8,
    (16, False): wu16,
    (32, False): wu32,
    (64, False): wu64,
}


def idiv(a: int, b: int) -> int:
    """C integer division: truncates toward zero; division by zero is a PLC fault."""
    if b == 0:
        raise PlcRuntimeError("divzero", "integer division by zero")
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def imod(a: int, b: int) -> int:
    """MatIEC's MOD: C remainder (sign of the dividend); x MOD 0 = 0."""
    if b == 0:
        return 0
    return a - b * idiv(a, b)


def fdiv(a: float, b: float) -> float:
    try:
        return a / b
    except ZeroDivisionError:
        if a != a or a == 0:
            return NAN
        neg = (a < 0) != (math.copysign(1.0, b) < 0)
        return -INF if neg else INF


def ix(i: int, lo: int, n: int) -> int:
    k = i - lo
    if 0 <= k < n:
        return k
    raise PlcRuntimeError("index", f"array index {i} out of range [{lo}..{lo + n - 1}]")


# ---------------------------------------------------------------- conversions
def _c_trunc_to_i64(x: float) -> int:
    """C (long long) cast of a double; x86 gives INT64_MIN for NaN and out-of-range values."""
    if x != x or x >= 9.2233720368547758e18 or x < -9.2233720368547758e18:
        return -0x8000000000000000
    return int(x)


def _real_round(x: float) -> int:
    if math.fmod(x, 1.0) == 0.0:
        t = _c_trunc_to_i64(x)
        q = abs(t) // 2
        return (q if t >= 0 else -q) * 2
    return _c_trunc_to_i64(x)


def real_to_sint(x: float) -> int:
    """MatIEC __real_to_sint: +-0.5 in binary64, then ties to even (64-bit result)."""
    return _real_round(x + 0.5) if x >= 0 else _real_round(x - 0.5)


def real_to_uint(x: float) -> int:
    return wu64(_real_round(x + 0.5)) if x >= 0 else 0


def trunc(x: float) -> int:
    return _c_trunc_to_i64(x)


# ---------------------------------------------------------------- TIME
def _split(ns: int) -> tuple[int, int]:
    s = abs(ns) // NS
    r = abs(ns) - s * NS
    return (s, r) if ns >= 0 else (-s, -r)


def _normalize(sec: int, nsec: int) -> int:
    if nsec < -NS or (sec > 0 and nsec < 0):
        sec -= 1
        nsec += NS
    if nsec > NS or (sec < 0 and nsec > 0):
        sec += 1
        nsec -= NS
    return sec * NS + nsec


def _c_long(x: float) -> int:
    return int(x) if x == x and abs(x) < 9.2e18 else -0x8000000000000000


def time_mul(t: int, k: float) -> int:
    sec, nsec = _split(t)
    s_f = sec * float(k)
    s = _c_long(s_f)
    prod = ws32(_c_long(float(nsec) * float(k)))
    quot = abs(prod) // NS * (1 if prod >= 0 else -1)
    rem = prod - quot * NS
    return _normalize(s + quot, _c_long(rem + (s_f - s) * 1e9))


def time_div(t: int, k: float) -> int:
    sec, nsec = _split(t)
    s_f = fdiv(float(sec), float(k))
    s = _c_long(s_f)
    return _normalize(s, _c_long(fdiv(float(nsec), float(k)) + (s_f - s) * 1e9))


def time_to_lreal(t: int) -> float:
    sec, nsec = _split(t)
    return float(sec) + float(nsec) / 1e9


def time_to_int(t: int) -> int:
    return _split(t)[0]


def real_to_time(x: float) -> int:
    sec = _c_long(x)
    return sec * NS + _c_long((x - sec) * 1e9)


def int_to_time(n: int) -> int:
    return n * NS


# 80-bit x87 long double, as MatIEC's TIME literal macro computes in it.
def _ld(x: Fraction) -> Fraction:
    if x == 0:
        return x
    sign = -1 if x < 0 else 1
    a = abs(x)
    e = a.numerator.bit_length() - a.denominator.bit_length()
    if Fraction(2) ** e > a:
        e -= 1
    scale = Fraction(2) ** (63 - e)  # 64-bit significand
    m = a * scale
    n = m.numerator // m.denominator
    rem = m - n
    if rem > Fraction(1, 2) or (rem == Fraction(1, 2) and n % 2 == 1):
        n += 1
    return sign * n / scale


def time_literal_ns(sign: int, ms: float, s: float, m: float, h: float, d: float) -> int:
    """MatIEC's __time_to_timespec macro evaluated in long double, truncated like C."""
    F = Fraction
    total = _ld(_ld(_ld(_ld(_ld(_ld(F(d) * 24) + F(h)) * 60) + F(m)) * 60) + F(s))
    total = _ld(total + _ld(F(ms) / F(1000)))
    total = total * (1 if sign >= 0 else -1)
    sec = int(total)  # truncation toward zero
    nsec = int(_ld((total - sec) * F(10**9)))
    return sec * NS + nsec


# ---------------------------------------------------------------- bit shifts
def shl(x: int, n: int, bits: int) -> int:
    return (x << n) & ((1 << bits) - 1) if 0 <= n < 4096 else 0


def shr(x: int, n: int, bits: int) -> int:
    return (x & ((1 << bits) - 1)) >> n if n >= 0 else 0


def rol(x: int, n: int, bits: int) -> int:
    n %= bits
    mask = (1 << bits) - 1
    x &= mask
    return ((x << n) | (x >> (bits - n))) & mask


def ror(x: int, n: int, bits: int) -> int:
    n %= bits
    mask = (1 << bits) - 1
    x &= mask
    return ((x >> n) | (x << (bits - n))) & mask


# ---------------------------------------------------------------- math (glibc-like)
def _m(fn):
    def call(x: float) -> float:
        try:
            return fn(x)
        except (ValueError, OverflowError):
            return _math_special(fn, x)

    return call


def _math_special(fn, x: float) -> float:
    if fn is math.exp:
        return INF if x > 0 else 0.0
    if fn in (math.log, math.log10):
        if x == 0:
            return -INF
        return NAN if x < 0 or x != x else INF
    if fn is math.sqrt:
        return NAN
    return NAN


sqrt = _m(math.sqrt)
exp = _m(math.exp)
ln = _m(math.log)
log10 = _m(math.log10)
sin = _m(math.sin)
cos = _m(math.cos)
tan = _m(math.tan)
asin = _m(math.asin)
acos = _m(math.acos)
atan = _m(math.atan)


def expt(a: float, b: float) -> float:
    try:
        r = math.pow(a, b)
    except ZeroDivisionError:
        return INF
    except (ValueError, OverflowError):
        if a < 0 and not float(b).is_integer():
            return NAN
        return INF
    return r


def limit(mn, x, mx):
    return (x if x < mx else mx) if x > mn else mn


def mux(k: int, *vals):
    return vals[k] if 0 <= k < len(vals) else 0


def abs_int(x: int) -> int:
    return -x if x < 0 else x


def abs_float(x: float) -> float:
    return -x if x < 0 else x  # MatIEC: (x < 0 ? -x : x), so ABS(-0.0) stays -0.0


# ---------------------------------------------------------------- REF_TO (read-only, as MatIEC compiles it)
class Ref:
    __slots__ = ("get",)

    def __init__(self, getter) -> None:
        self.get = getter


def deref(r: Ref | None):
    if r is None:
        raise PlcRuntimeError("other", "dereference of a NULL reference")
    return r.get()
