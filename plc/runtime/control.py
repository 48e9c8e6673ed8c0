"""The soft-PLC control block: holding registers 60000.. (an extension; OpenPLC has none).

Stepping (stepped mode only), fault reset and status. 32/64-bit values are served high
word first like the rest of the map. The layout is documented in docs/softplc.md and
docs/internal-interfaces.md; `CONTROL_BLOCK_VERSION` changes when it does.
"""

from __future__ import annotations

from dataclasses import dataclass

CONTROL_BASE = 60000
STEP = CONTROL_BASE + 0  # W (stepped mode): run N scans, then acknowledge
COMMAND = CONTROL_BASE + 1  # W: 1 = reset fault
RW_STEPS = CONTROL_BASE + 2  # W (stepped mode): scans run inside every FC23 between its write and its read
STATUS = CONTROL_BASE + 3  # R: 0 running, 1 stopped by a fault
FAULT_CODE = CONTROL_BASE + 4  # R: 0 none, 1 index, 2 division by zero, 9 other
MODE = CONTROL_BASE + 5  # R: 0 real time, 1 stepped
VERSION = CONTROL_BASE + 6  # R: layout version
SCAN_COUNT = CONTROL_BASE + 8  # R: u32 completed scans
PLC_TIME_MS = CONTROL_BASE + 10  # R: u32
PLC_TIME_NS = CONTROL_BASE + 12  # R: u64
INTERVAL_NS = CONTROL_BASE + 16  # R: u64
OVERRUNS = CONTROL_BASE + 20  # R: u32 real-time scans started more than one interval late
FAULT_TEXT = CONTROL_BASE + 22  # R: ASCII, 2 chars per word, NUL padded
FAULT_TEXT_WORDS = 64
CONTROL_SIZE = FAULT_TEXT + FAULT_TEXT_WORDS - CONTROL_BASE

CONTROL_BLOCK_VERSION = 1
MAX_STEP = 0xFFFF

COMMAND_NONE = 0
COMMAND_RESET_FAULT = 1

STATUS_RUNNING = 0
STATUS_FAULTED = 1

MODE_REALTIME = 0
MODE_STEPPED = 1

FAULT_NONE = 0
FAULT_INDEX = 1
FAULT_DIVISION_BY_ZERO = 2
FAULT_OTHER = 9


def in_control_block(address: int, count: int) -> bool:
    """True when [address, address+count) lies inside the control block."""
    return CONTROL_BASE <= address and address + count <= CONTROL_BASE + CONTROL_SIZE and count >= 1


@dataclass(frozen=True)
class PlcStatus:
    """Decoded control block (what `RawModbusClient.status()` returns)."""

    status: int
    rw_steps: int
    fault_code: int
    scan_count: int
    time_ns: int
    time_ms: int
    interval_ns: int
    mode: int
    version: int
    overruns: int
    fault_text: str

    @property
    def faulted(self) -> bool:
        return self.status == STATUS_FAULTED

    @property
    def stepped(self) -> bool:
        return self.mode == MODE_STEPPED


def decode_status(words: list[int]) -> PlcStatus:
    """Decode the whole control block read from `CONTROL_BASE` (CONTROL_SIZE words)."""
    from plc.runtime.codec import words_to_int, words_to_text

    def at(address: int, n_words: int) -> list[int]:
        start = address - CONTROL_BASE
        return words[start : start + n_words]

    return PlcStatus(
        status=words[STATUS - CONTROL_BASE],
        rw_steps=words[RW_STEPS - CONTROL_BASE],
        fault_code=words[FAULT_CODE - CONTROL_BASE],
        scan_count=words_to_int(at(SCAN_COUNT, 2)),
        time_ns=words_to_int(at(PLC_TIME_NS, 4)),
        time_ms=words_to_int(at(PLC_TIME_MS, 2)),
        interval_ns=words_to_int(at(INTERVAL_NS, 4)),
        mode=words[MODE - CONTROL_BASE],
        version=words[VERSION - CONTROL_BASE],
        overruns=words_to_int(at(OVERRUNS, 2)),
        fault_text=words_to_text(at(FAULT_TEXT, FAULT_TEXT_WORDS)),
    )
