"""Runtime faults of a running PLC program (they stop the program, never the process)."""

from __future__ import annotations


class PlcRuntimeError(Exception):
    """Array index out of range, integer division by zero, ... in the ST program."""

    #: numeric fault codes readable over Modbus (soft-PLC status registers)
    CODES = {"index": 1, "divzero": 2, "other": 9}

    def __init__(self, kind: str, message: str):
        self.kind = kind
        self.code = self.CODES.get(kind, self.CODES["other"])
        super().__init__(message)
