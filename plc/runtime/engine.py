"""Scan engine: runs an `Application` scan by scan, catches runtime faults, serves the control block.

A runtime fault (array index, integer division by zero, or any error inside the
interpreter) stops the PLC program, never the process: the fault is logged and kept in
`fault_code` / `fault_text` until a reset. Every access to the application (scans and
Modbus requests) happens under `lock`.
"""

from __future__ import annotations

import logging
import threading
from typing import Protocol

from plc.runtime import codec, control
from plc.runtime.addressmap import ModbusError

log = logging.getLogger("thermost.plc")

NS_PER_MS = 1_000_000
U32_MASK = 0xFFFFFFFF
U64_MASK = 0xFFFFFFFFFFFFFFFF


class ApplicationLike(Protocol):
    """What the engine needs from `plc.st.compiler.Application`."""

    interval_ns: int
    time_ns: int
    located: list

    def scan(self) -> None: ...

    def reset_fault(self) -> None: ...


def _fault_code_of(exc: BaseException) -> int:
    code = getattr(exc, "code", None)
    if isinstance(code, int) and code > 0:
        return code
    return control.FAULT_OTHER


class PlcEngine:
    """The PLC program plus its scan counter, fault state and control block."""

    def __init__(self, app: ApplicationLike, stepped: bool):
        self.app = app
        self.stepped = stepped
        self.lock = threading.Lock()
        self.scan_count = 0
        self.overruns = 0
        self.fault_code = control.FAULT_NONE
        self.fault_text = ""
        self._fault_text_words = codec.text_to_words("", control.FAULT_TEXT_WORDS)
        self.last_step = 0
        self.last_command = control.COMMAND_NONE
        self.rw_steps = 0
        self._fault_text_words = codec.text_to_words("", control.FAULT_TEXT_WORDS)

    @property
    def faulted(self) -> bool:
        return self.fault_code != control.FAULT_NONE

    @property
    def interval_ns(self) -> int:
        return int(self.app.interval_ns)

    # -- scanning (caller holds the lock) ---------------------------------------------------
    def scan_once(self) -> bool:
        """One scan unless the program is stopped by a fault; False when it is (or becomes) stopped."""
        if self.faulted:
            return False
        try:
            self.app.scan()
        except Exception as exc:  # noqa: BLE001 - a program fault must never kill the runtime
            self._record_fault(exc)
            return False
        self.scan_count += 1
        return True

    def step(self, n_scans: int) -> bool:
        """Run up to `n_scans` scans; stop at the first fault. True when all ran."""
        for _ in range(n_scans):
            if not self.scan_once():
                return False
        return True

    def _record_fault(self, exc: Exception) -> None:
        self.fault_code = _fault_code_of(exc)
        prefix = "" if hasattr(exc, "kind") else f"internal error {type(exc).__name__}: "
        self.fault_text = f"{prefix}{exc}" or type(exc).__name__
        self._fault_text_words = codec.text_to_words(self.fault_text, control.FAULT_TEXT_WORDS)
        log.error(
            "PLC program stopped by a runtime fault in scan %d (code %d): %s",
            self.scan_count + 1,
            self.fault_code,
            self.fault_text,
            exc_info=not hasattr(exc, "kind"),
        )

    def reset_fault(self) -> None:
        """Clear the fault; the program resumes from its current state at the next scan."""
        if not self.faulted:
            return
        reset = getattr(self.app, "reset_fault", None)
        if callable(reset):
            reset()
        log.warning("fault reset (code %d: %s); PLC program resumes", self.fault_code, self.fault_text)
        self.fault_code = control.FAULT_NONE
        self.fault_text = ""
        self._fault_text_words = codec.text_to_words("", control.FAULT_TEXT_WORDS)

    # -- control block (caller holds the lock) ----------------------------------------------
    def control_words(self) -> list[int]:
        """The whole control block, CONTROL_SIZE words from CONTROL_BASE."""
        words = [0] * control.CONTROL_SIZE

        def put(address: int, value_words: list[int]) -> None:
            start = address - control.CONTROL_BASE
            words[start : start + len(value_words)] = value_words

        time_ns = int(self.app.time_ns)
        put(control.STEP, [self.last_step])
        put(control.COMMAND, [self.last_command])
        put(control.RW_STEPS, [self.rw_steps])
        put(control.STATUS, [control.STATUS_FAULTED if self.faulted else control.STATUS_RUNNING])
        put(control.FAULT_CODE, [self.fault_code])
        put(control.SCAN_COUNT, codec.int_to_words(self.scan_count & U32_MASK, 2))
        put(control.PLC_TIME_NS, codec.int_to_words(time_ns & U64_MASK, 4))
        put(control.PLC_TIME_MS, codec.int_to_words((time_ns // NS_PER_MS) & U32_MASK, 2))
        put(control.INTERVAL_NS, codec.int_to_words(self.interval_ns & U64_MASK, 4))
        put(control.MODE, [control.MODE_STEPPED if self.stepped else control.MODE_REALTIME])
        put(control.VERSION, [control.CONTROL_BLOCK_VERSION])
        put(control.OVERRUNS, codec.int_to_words(self.overruns & U32_MASK, 2))
        put(control.FAULT_TEXT, self._fault_text_words)
        return words

    def read_control(self, address: int, count: int) -> list[int] | ModbusError:
        if not control.in_control_block(address, count):
            return ModbusError.ILLEGAL_ADDRESS
        start = address - control.CONTROL_BASE
        if start + count <= control.STATUS - control.CONTROL_BASE:  # only the writable registers
            return [self.last_step, self.last_command, self.rw_steps][start : start + count]
        return self.control_words()[start : start + count]

    def write_control(self, address: int, values: list[int]) -> ModbusError | None:
        """Writes to STEP / COMMAND, in address order; other control registers are read only."""
        if not control.in_control_block(address, len(values)):
            return ModbusError.ILLEGAL_ADDRESS
        writable = {control.COMMAND} | ({control.STEP, control.RW_STEPS} if self.stepped else set())
        targets = range(address, address + len(values))
        if any(addr not in writable for addr in targets):
            return ModbusError.ILLEGAL_ADDRESS
        for addr, value in zip(targets, values, strict=True):
            result = self._write_one(addr, value)
            if result is not None:
                return result
        return None

    def _write_one(self, address: int, value: int) -> ModbusError | None:
        if address == control.COMMAND:
            if value not in (control.COMMAND_NONE, control.COMMAND_RESET_FAULT):
                return ModbusError.ILLEGAL_VALUE
            self.last_command = value
            if value == control.COMMAND_RESET_FAULT:
                self.reset_fault()
            return None
        if address == control.RW_STEPS:
            self.rw_steps = value
            return None
        if not 1 <= value <= control.MAX_STEP:
            return ModbusError.ILLEGAL_VALUE
        self.last_step = value
        return None if self.step(value) else ModbusError.DEVICE_FAILURE
