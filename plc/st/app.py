"""A loaded ST application: program instances, PLC clock and located variables."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from plc.st.errors import PlcRuntimeError


@dataclass
class Location:
    """A located variable as declared, its location parsed."""

    name: str
    instance: str  # program instance ("" for a CONFIGURATION global)
    location: str  # e.g. "%MD3"
    area: str  # I Q M
    size: str  # X B W D L
    index: int
    bit: int | None
    iec_type: str


@dataclass
class LocatedVar(Location):
    """A located variable of a loaded application, with its accessors."""

    get: Callable[[], Any]
    set: Callable[[Any], None]


class Application:
    def __init__(
        self,
        clock,
        programs: dict,
        intervals: dict[str, int],
        located: list[LocatedVar],
        globals_obj,
        code: str,
    ):
        self.clock = clock
        self.programs = programs
        self.located = located
        self.globals = globals_obj
        self.code = code
        known = [iv for iv in intervals.values() if iv > 0]
        self.interval_ns = math.gcd(*known) if known else 10_000_000
        # each instance runs every `ratio` ticks (OpenPLC: tasks at multiples of the common tick)
        self._schedule = [
            (obj, max(1, intervals[name] // self.interval_ns) if intervals[name] else 1)
            for name, obj in programs.items()
        ]
        self.tick = 0
        self.fault: PlcRuntimeError | None = None

    @property
    def time_ns(self) -> int:
        return self.clock.ns

    def scan(self) -> None:
        if self.fault is not None:
            return
        try:
            for obj, ratio in self._schedule:
                if self.tick % ratio == 0:
                    obj._run()
        except PlcRuntimeError as exc:
            self.fault = exc
            raise
        except (RecursionError, ZeroDivisionError, OverflowError, ValueError, TypeError, IndexError) as exc:
            self.fault = PlcRuntimeError("other", f"{type(exc).__name__}: {exc}")
            raise self.fault from exc
        self.tick += 1
        self.clock.ns += self.interval_ns

    def reset_fault(self) -> None:
        self.fault = None

    # -------------------------------------------------------------- dotted access for tests and tools
    def _walk(self, path: str):
        parts = path.replace("]", "").replace("[", ".[").split(".")
        head = parts[0].lower()
        if head in self.programs:
            obj = self.programs[head]
        elif hasattr(self.globals, f"v_{head}"):
            obj = getattr(self.globals, f"v_{head}")
            parts = ["", *parts]  # the global itself was the first step
            obj = self.globals
            parts = parts[1:]
            return self._descend(obj, parts)
        else:
            raise KeyError(f"no program instance or global named '{parts[0]}'")
        return self._descend(obj, parts[1:])

    @staticmethod
    def _descend(obj, parts: list[str]):
        if not parts:
            raise KeyError("path names no variable")
        for p in parts[:-1]:
            obj = obj[int(p[1:])] if p.startswith("[") else getattr(obj, f"v_{p.lower()}")
        last = parts[-1]
        return obj, (int(last[1:]) if last.startswith("[") else f"v_{last.lower()}")

    def get(self, path: str) -> Any:
        obj, key = self._walk(path)
        if isinstance(key, int):
            return obj[key]
        try:
            return getattr(obj, key)
        except AttributeError:
            raise KeyError(path) from None

    def set(self, path: str, value: Any) -> None:
        """Raw set (no type conversion beyond what the caller gives); use for tests and tools."""
        obj, key = self._walk(path)
        if isinstance(key, int):
            obj[key] = value
        else:
            if not hasattr(obj, key):
                raise KeyError(path)
            setattr(obj, key, value)
