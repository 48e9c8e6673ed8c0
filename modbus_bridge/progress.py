"""Progress of `thermost run`: one bar per controller variant (rich), total = the planned plant time
(the figures are seconds of plant time).

The plan counts an event phase (`until = "tuned"`) at its timeout until the event comes; then the total
shrinks to what the run really needs, so a run that completes ends at 100 %. When stderr is not a
terminal (a log file, CI), plain lines instead: one per variant every PLAIN_EVERY_S of wall time and
one at its end. `quiet_libraries()` keeps pymodbus' own log lines out of the output unless -v.
"""

from __future__ import annotations

import logging
import sys
import time
from collections.abc import Callable
from typing import TextIO

PLAIN_EVERY_S = 5.0
LIBRARY_LOGGERS = ("pymodbus", "asyncio", "matplotlib")

VariantProgress = Callable[[float, float], None]


def quiet_libraries(verbose: bool) -> None:
    """Library log lines (pymodbus connection errors, ...) only with -v; our own one-line errors stay."""
    for name in LIBRARY_LOGGERS:
        logging.getLogger(name).setLevel(logging.DEBUG if verbose else logging.CRITICAL)
    if verbose:
        logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(name)s: %(message)s")


class RunProgress:
    """`with RunProgress(names) as p: p.update(index, done_s, total_s)`; disabled: does nothing."""

    def __init__(self, names: list[str], *, enabled: bool = True, stream: TextIO | None = None,
                 terminal: bool | None = None) -> None:
        self.names = names
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        isatty = getattr(self.stream, "isatty", lambda: False)
        self.terminal = isatty() if terminal is None else terminal
        self._progress = None
        self._tasks: list = []
        self._last_line = [0.0] * len(names)
        self._state = [(0.0, 0.0)] * len(names)
        self._ended = [False] * len(names)

    def __enter__(self) -> RunProgress:
        if self.enabled and self.terminal:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                Progress,
                ProgressColumn,
                TaskProgressColumn,
                TextColumn,
                TimeElapsedColumn,
            )
            from rich.text import Text

            class PlantTimeColumn(ProgressColumn):
                def render(self, task) -> Text:
                    if not task.total:
                        return Text("starting")
                    return Text(f"{task.completed:>5.0f}/{task.total:.0f} s")

            self._progress = Progress(
                TextColumn("[bold]{task.description:<18}"),
                BarColumn(bar_width=30),
                TaskProgressColumn(),
                PlantTimeColumn(),
                TimeElapsedColumn(),
                console=Console(file=self.stream),
                transient=False,
            )
            self._progress.start()
            self._tasks = [self._progress.add_task(n, total=None) for n in self.names]
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def callback(self, index: int) -> VariantProgress:
        return lambda done, total: self.update(index, done, total)

    def update(self, index: int, done: float, total: float) -> None:
        if not self.enabled or total <= 0:
            return
        self._state[index] = (done, total)
        if self._progress is not None:
            self._progress.update(self._tasks[index], completed=done, total=total)
            return
        now = time.monotonic()
        finished = done >= total - 1e-9
        if finished and not self._ended[index]:
            self._ended[index] = True
        elif now - self._last_line[index] < PLAIN_EVERY_S or finished:
            return
        self._last_line[index] = now
        self.stream.write(f"thermost: {self.names[index]}: {done:.0f}/{total:.0f} s plant time "
                          f"({100.0 * done / total:.0f} %)\n")
        self.stream.flush()

    def close(self) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None


class CountProgress:
    """A counted bar (experiments, scenarios) in the same style as `thermost run`'s:
    `with CountProgress("optimise seed003", total=40, unit="exp") as p: p.advance(note="best J 1.2")`.
    Plain lines when stderr is not a terminal; nothing when disabled."""

    def __init__(self, description: str, total: int, unit: str, *, enabled: bool = True,
                 stream: TextIO | None = None, terminal: bool | None = None) -> None:
        self.description = description
        self.total = total
        self.unit = unit
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        isatty = getattr(self.stream, "isatty", lambda: False)
        self.terminal = isatty() if terminal is None else terminal
        self.done = 0
        self.note = ""
        self._progress = None
        self._task = None
        self._last_line = 0.0

    def __enter__(self) -> CountProgress:
        if self.enabled and self.terminal:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._progress = Progress(
                TextColumn("[bold]{task.description}"),
                BarColumn(bar_width=30),
                MofNCompleteColumn(),
                TextColumn(self.unit),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
                TextColumn("{task.fields[note]}"),
                console=Console(file=self.stream),
                transient=False,
            )
            self._progress.start()
            self._task = self._progress.add_task(self.description, total=self.total, note="")
        return self

    def __exit__(self, *exc: object) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None

    def advance(self, step: int = 1, note: str | None = None) -> None:
        self.done += step
        if note is not None:
            self.note = note
        if not self.enabled:
            return
        if self._progress is not None:
            self._progress.update(self._task, advance=step, note=self.note)
            return
        now = time.monotonic()
        if now - self._last_line < PLAIN_EVERY_S and self.done < self.total:
            return
        self._last_line = now
        tail = f", {self.note}" if self.note else ""
        self.stream.write(f"thermost: {self.description}: {self.done}/{self.total} {self.unit}{tail}\n")
        self.stream.flush()

    def describe(self, note: str) -> None:
        """Change the note without advancing (e.g. the scenario now being scored)."""
        self.note = note
        if self._progress is not None:
            self._progress.update(self._task, note=note)
