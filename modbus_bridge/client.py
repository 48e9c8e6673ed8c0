"""Typed Modbus client of one PLC, addressed by tag name through the register map.

One connection per PLC (reference/openplc.md: the upstream runtime garbles replies when several
sockets talk at once), requests strictly sequential, and a garbled or timed-out reply is retried on
a fresh connection. 32-bit and 64-bit values use OpenPLC's word order (high word first).
Stepping (soft-PLC extension, docs/softplc.md): STEP register 60000; a step whose reply was lost is
not blindly repeated: the scan counter tells how many scans still have to run.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from pymodbus.client import AsyncModbusTcpClient
from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

from plc.runtime import control as ctl  # control block layout of the soft-PLC

from .regmap import COIL, DISCRETE, HOLDING, INPUT, RegisterMap, Tag

STEP_REGISTER = ctl.STEP
RW_STEPS_REGISTER = ctl.RW_STEPS
SCAN_COUNT_REGISTER = ctl.SCAN_COUNT
MODE_REGISTER = ctl.MODE
INTERVAL_NS_REGISTER = ctl.INTERVAL_NS
FAULT_TEXT_REGISTER = ctl.FAULT_TEXT
FAULT_TEXT_WORDS = ctl.FAULT_TEXT_WORDS
MAX_READ_REGISTERS = 125  # Modbus limit per read request
MAX_WRITE_REGISTERS = 123
MAX_READ_BITS = 2000
DEVICE_ID = 1
DT = AsyncModbusTcpClient.DATATYPE
CODECS = {
    "REAL": DT.FLOAT32,
    "LREAL": DT.FLOAT64,
    "DINT": DT.INT32,
    "UDINT": DT.UINT32,
    "DWORD": DT.UINT32,
    "TIME": DT.INT32,
    "INT": DT.INT16,
    "UINT": DT.UINT16,
    "WORD": DT.UINT16,
    "SINT": DT.INT16,
    "USINT": DT.UINT16,
    "BYTE": DT.UINT16,
    "LINT": DT.INT64,
    "ULINT": DT.UINT64,
    "LWORD": DT.UINT64,
}
INT_RANGES = {
    "INT": (-(1 << 15), (1 << 15) - 1),
    "UINT": (0, (1 << 16) - 1),
    "WORD": (0, (1 << 16) - 1),
    "DINT": (-(1 << 31), (1 << 31) - 1),
    "UDINT": (0, (1 << 32) - 1),
    "DWORD": (0, (1 << 32) - 1),
    "SINT": (-128, 127),
    "USINT": (0, 255),
    "BYTE": (0, 255),
}


class PlcError(RuntimeError):
    """The PLC is unreachable, stopped answering, faulted, or refused a request (one clear line)."""


def encode(tag: Tag, value: float | int | bool) -> list[int]:
    if tag.is_bit:
        raise TypeError(f"{tag.name} is a BOOL coil")
    if tag.iec_type in ("REAL", "LREAL"):
        return AsyncModbusTcpClient.convert_to_registers(float(value), CODECS[tag.iec_type], word_order="big")
    ivalue = int(value)
    lo, hi = INT_RANGES.get(tag.iec_type, (-(1 << 63), (1 << 64) - 1))
    if not lo <= ivalue <= hi:
        raise ValueError(f"{tag.name}: {value} does not fit {tag.iec_type}")
    return AsyncModbusTcpClient.convert_to_registers(ivalue, CODECS[tag.iec_type], word_order="big")


def decode(tag: Tag, words: Sequence[int]) -> float | int:
    value = AsyncModbusTcpClient.convert_from_registers(list(words), CODECS[tag.iec_type], word_order="big")
    if tag.iec_type in ("SINT",) and isinstance(value, int):
        value = (value + 128) % 256 - 128
    return value  # type: ignore[return-value]


@dataclass
class _Span:
    table: str
    start: int
    count: int
    tags: list[Tag]


def plan_reads(tags: Iterable[Tag]) -> list[_Span]:
    """Group tags into as few read requests as possible: per table, each span as long as one request may
    read, across the holes between tags (a round trip costs more than the unused words; OpenPLC and the
    soft-PLC answer every address below 8192, 0 where no variable is located). Filling each span from the
    lowest address left is the fewest spans of that length that cover the tags."""
    spans: list[_Span] = []
    for table in (HOLDING, INPUT, COIL, DISCRETE):
        group = sorted((t for t in tags if t.table == table), key=lambda t: t.address)
        limit = MAX_READ_BITS if table in (COIL, DISCRETE) else MAX_READ_REGISTERS
        for t in group:
            end = t.address + max(t.words, 1)
            if spans and spans[-1].table == table and end - spans[-1].start <= limit:
                last = spans[-1]
                last.count = max(last.count, end - last.start)
                last.tags.append(t)
            else:
                spans.append(_Span(table, t.address, end - t.address, [t]))
    return spans


class PlcClient:
    """Async client of one PLC. Use `async with PlcClient(host, port, regmap) as plc:`."""

    def __init__(
        self,
        host: str,
        port: int,
        regmap: RegisterMap,
        timeout_s: float = 1.0,
        retries: int = 2,
        name: str = "PLC",
    ) -> None:
        self.host, self.port, self.regmap = host, port, regmap
        self.timeout_s, self.retries, self.name = timeout_s, retries, name
        self._client: AsyncModbusTcpClient | None = None
        self._expected_scans: int | None = None
        self._rw_steps = 0
        self._plans: dict[tuple[str, ...], list[_Span]] = {}
        self.retried = 0

    async def __aenter__(self) -> PlcClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        self.close()

    @property
    def where(self) -> str:
        return f"{self.name} at {self.host}:{self.port}"

    async def connect(self) -> None:
        self.close()
        # pymodbus' own retries are off: this class retries on a fresh connection instead
        client = AsyncModbusTcpClient(
            self.host, port=self.port, timeout=self.timeout_s, retries=0, reconnect_delay=0
        )
        try:
            ok = await client.connect()
        except (OSError, ModbusException) as exc:
            raise PlcError(f"cannot connect to {self.where}: {exc}") from None
        if not ok:
            client.close()
            raise PlcError(f"cannot connect to {self.where} (connection refused or timed out)")
        self._client = client

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    async def _call(self, what: str, fn_name: str, *args, retry: bool = True, **kwargs):
        """One request; on a timeout, a broken connection or a garbled reply: reconnect and retry."""
        last = ""
        for attempt in range(self.retries + 1 if retry else 1):
            try:
                if self._client is None:
                    await self.connect()
                assert self._client is not None
                reply = await getattr(self._client, fn_name)(*args, device_id=DEVICE_ID, **kwargs)
            except (TimeoutError, ModbusIOException, ConnectionException, OSError) as exc:
                last = f"{type(exc).__name__}: {exc}".strip()
                self.retried += attempt < self.retries
                self.close()
                continue
            if reply.isError():
                code = getattr(reply, "exception_code", None)
                raise PlcError(f"{self.where} refused {what}: Modbus exception {code}")
            return reply
        raise PlcError(f"{self.where} stopped answering ({what}; {last or 'no reply'})")

    # --- typed access by tag name -------------------------------------------------------------------
    async def read(self, name: str) -> float | int | bool:
        return (await self.read_tags([name]))[name]

    async def write(self, name: str, value: float | int | bool) -> None:
        await self.write_tags({name: value})

    def _plan(self, names: Iterable[str]) -> list[_Span]:
        key = tuple(names)
        plan = self._plans.get(key)
        if plan is None:
            plan = self._plans[key] = plan_reads([self.regmap[n] for n in key])
        return plan

    async def read_tags(self, names: Iterable[str]) -> dict[str, float | int | bool]:
        out: dict[str, float | int | bool] = {}
        for span in self._plan(names):
            values = await self._read_span(span)
            self._unpack(span, values, out)
        return out

    async def _read_span(self, span: _Span) -> list:
        what = f"read of {span.count} {span.table}(s) at {span.start}"
        if span.table == HOLDING:
            return list(
                (await self._call(what, "read_holding_registers", span.start, count=span.count)).registers
            )
        if span.table == INPUT:
            return list(
                (await self._call(what, "read_input_registers", span.start, count=span.count)).registers
            )
        if span.table == COIL:
            return list((await self._call(what, "read_coils", span.start, count=span.count)).bits)
        return list((await self._call(what, "read_discrete_inputs", span.start, count=span.count)).bits)

    @staticmethod
    def _unpack(span: _Span, values: Sequence, out: dict) -> None:
        for t in span.tags:
            off = t.address - span.start
            out[t.name] = bool(values[off]) if t.is_bit else decode(t, values[off : off + t.words])

    def _encode_writes(
        self, values: Mapping[str, float | int | bool]
    ) -> tuple[dict[int, int], dict[int, bool]]:
        words: dict[int, int] = {}
        bits: dict[int, bool] = {}
        for name, value in values.items():
            tag = self.regmap[name]
            if not tag.writable:
                raise PlcError(f"{name} ({tag.location}) is read-only for a Modbus client")
            if isinstance(value, float) and math.isnan(value) and tag.iec_type not in ("REAL", "LREAL"):
                raise ValueError(f"{name}: NaN for {tag.iec_type}")
            if tag.is_bit:
                bits[tag.address] = bool(value)
            else:
                for k, w in enumerate(encode(tag, value)):
                    words[tag.address + k] = w
        return words, bits

    async def write_tags(self, values: Mapping[str, float | int | bool]) -> None:
        """Contiguous holding registers go out in one FC16 request, coils in FC15 requests."""
        words, bits = self._encode_writes(values)
        for start, block in _runs(words, MAX_WRITE_REGISTERS):
            await self._call(f"write of {len(block)} register(s) at {start}", "write_registers", start, block)
        for start, block in _runs(bits, MAX_READ_BITS):
            await self._call(f"write of {len(block)} coil(s) at {start}", "write_coils", start, block)

    # --- soft-PLC control block ---------------------------------------------------------------------
    async def scan_count(self) -> int:
        r = await self._call(
            "read of the scan counter", "read_holding_registers", SCAN_COUNT_REGISTER, count=2
        )
        return (r.registers[0] << 16) | r.registers[1]

    async def stepped(self) -> bool:
        """True for a soft-PLC in stepped mode; False for real time or a PLC without the control block
        (a real OpenPLC answers those addresses with an exception)."""
        try:
            r = await self._call("read of the clock mode", "read_holding_registers", MODE_REGISTER, count=1)
        except PlcError as exc:
            if "refused" in str(exc):
                return False
            raise
        return r.registers[0] == ctl.MODE_STEPPED

    async def fault_text(self) -> str:
        r = await self._call(
            "read of the fault text", "read_holding_registers", FAULT_TEXT_REGISTER, count=FAULT_TEXT_WORDS
        )
        raw = b"".join(w.to_bytes(2, "big") for w in r.registers)
        return raw.split(b"\0", 1)[0].decode("ascii", "replace")

    async def step(self, scans: int = 1) -> None:
        """Run `scans` PLC scans (stepped soft-PLC), through the STEP register."""
        await self._stepping(scans, None, None)

    async def step_and_read(self, scans: int, names: Sequence[str]) -> dict[str, float | int | bool]:
        """Step `scans` scans, then read the named tags."""
        return await self.exchange({}, scans, names)

    async def exchange(
        self, writes: Mapping[str, float | int | bool], scans: int, names: Sequence[str]
    ) -> dict[str, float | int | bool]:
        """One harness step on a stepped soft-PLC in as few requests as possible: coils and scattered
        registers first (FC15/FC16), then ONE FC23 that writes the largest contiguous block of input
        registers, runs `scans` scans (RW_STEPS, docs/internal-interfaces.md) and reads the first span
        of outputs; other output spans are read after it."""
        words, bits = self._encode_writes(writes)
        runs = _runs(words, MAX_WRITE_REGISTERS)
        block = max(runs, key=lambda r: len(r[1])) if runs else None
        for start, values in runs:
            if block is None or start != block[0]:
                await self._call(
                    f"write of {len(values)} register(s) at {start}", "write_registers", start, values
                )
        for start, values in _runs(bits, MAX_READ_BITS):
            await self._call(f"write of {len(values)} coil(s) at {start}", "write_coils", start, values)
        spans = self._plan(names)
        out: dict[str, float | int | bool] = {}
        first = spans[0] if spans and spans[0].table == HOLDING else None
        if block is not None and first is not None:
            if self._rw_steps != scans:
                await self._call("set RW_STEPS", "write_register", RW_STEPS_REGISTER, scans)
                self._rw_steps = scans
            registers = await self._stepping(scans, first, block)
        else:
            if block is not None:
                await self._call(
                    f"write of {len(block[1])} register(s)", "write_registers", block[0], block[1]
                )
            registers = await self._stepping(scans, first, None)
        if first is not None:
            self._unpack(first, registers, out)
            spans = spans[1:]
        for span in spans:
            self._unpack(span, await self._read_span(span), out)
        return out

    async def _stepping(self, scans: int, span: _Span | None, block: tuple[int, list] | None) -> list[int]:
        """Scans are not idempotent: a step is never retried blindly. The expected scan counter is kept;
        after a lost reply the counter says how many scans really ran, and only the rest is requested.
        block given: FC23 writing it with RW_STEPS = scans; else the STEP register (FC6 when the RW_STEPS
        mode is on, so scans are not doubled, else FC23 STEP + read)."""
        if self._expected_scans is None:
            self._expected_scans = await self.scan_count()
        target = self._expected_scans + scans
        remaining = scans
        for _attempt in range(self.retries + 1):
            try:
                registers: list[int] = []
                if block is not None and remaining == scans:
                    reply = await self._call(
                        f"write, {scans} scan(s) and read",
                        "readwrite_registers",
                        read_address=span.start,
                        read_count=span.count,
                        write_address=block[0],
                        values=block[1],
                        retry=False,
                    )
                    registers = list(reply.registers)
                elif span is None or self._rw_steps:
                    await self._call(
                        f"step of {remaining} scan(s)",
                        "write_register",
                        STEP_REGISTER,
                        remaining,
                        retry=False,
                    )
                    if span is not None:
                        registers = await self._read_span(span)
                else:
                    reply = await self._call(
                        f"step of {remaining} scan(s) with read",
                        "readwrite_registers",
                        read_address=span.start,
                        read_count=span.count,
                        write_address=STEP_REGISTER,
                        values=[remaining],
                        retry=False,
                    )
                    registers = list(reply.registers)
                self._expected_scans = target
                return registers
            except PlcError as exc:
                if "exception 4" in str(exc):
                    raise PlcError(
                        f"{self.where}: PLC program stopped by a runtime fault: {await self.fault_text()}"
                    ) from None
                if "refused" in str(exc):
                    raise
                self.retried += 1
                done_now = await self.scan_count()
                remaining = target - done_now
                if remaining <= 0:
                    self._expected_scans = done_now
                    return [] if span is None else await self._read_span(span)
        raise PlcError(f"{self.where} stopped answering (step of {scans} scan(s))")


def _runs(cells: Mapping[int, int | bool], limit: int) -> list[tuple[int, list]]:
    runs: list[tuple[int, list]] = []
    for addr in sorted(cells):
        if runs and runs[-1][0] + len(runs[-1][1]) == addr and len(runs[-1][1]) < limit:
            runs[-1][1].append(cells[addr])
        else:
            runs.append((addr, [cells[addr]]))
    return runs
