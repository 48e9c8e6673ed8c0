"""Controller variants side by side in forked worker processes, and how a run is stopped.

Every worker loads its own stepped soft-PLC, so a comparison costs the wall time of one run on a
multi-core machine. SIGINT and SIGTERM never kill a worker outright: the parent sets a shared stop
flag, every worker ends its run at the next plant step and sends the trace measured so far (the
report says it is partial), and workers that do not answer within STOP_GRACE_S are killed. A worker
whose parent died stops by itself. `Interrupts` does the same for the single-process paths.
"""

from __future__ import annotations

import asyncio
import dataclasses
import os
import queue as queue_mod
import signal
import time
from collections.abc import Callable
from pathlib import Path
from types import FrameType

from .analysis import PhaseMetrics, run_metrics
from .loop import ProgressFn, RunResult
from .runner import HarnessSetup, ProgressFor, run_variants
from .scenario import Scenario

STOP_GRACE_S = 1.0  # after a stop request, workers have this long to hand in their partial trace
POLL_S = 0.2
SIGNAL_NAMES = {signal.SIGINT: "SIGINT", signal.SIGTERM: "SIGTERM"}


class Interrupts:
    """`with Interrupts() as stop:` SIGINT/SIGTERM set `stop.reason` instead of killing the process;
    `stop()` returns the reason (a `should_stop` for the loop). A second signal raises KeyboardInterrupt.
    An asyncio task may be registered with `cancel_after_grace` so a run blocked on a dead PLC ends too."""

    def __init__(self, on_signal: Callable[[str], None] | None = None) -> None:
        self.reason: str | None = None
        self.on_signal = on_signal
        self._previous: dict[int, object] = {}
        self._task: asyncio.Task | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    def __call__(self) -> str | None:
        return self.reason

    def _handle(self, signum: int, _frame: FrameType | None) -> None:
        if self.reason is not None:
            raise KeyboardInterrupt
        self.reason = f"interrupted by {SIGNAL_NAMES.get(signum, signum)}"
        if self.on_signal is not None:
            self.on_signal(self.reason)
        if self._task is not None and self._loop is not None:
            self._loop.call_soon_threadsafe(self._loop.call_later, STOP_GRACE_S, self._task.cancel)

    def cancel_after_grace(self, task: asyncio.Task) -> None:
        self._task, self._loop = task, task.get_loop()

    def __enter__(self) -> Interrupts:
        for sig in SIGNAL_NAMES:
            self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)  # type: ignore[arg-type]


def run_async_interruptible(coro_factory: Callable[[Interrupts], object]) -> object:
    """asyncio.run of `coro_factory(stop)` with SIGINT/SIGTERM turned into a stop request."""

    async def main(stop: Interrupts):
        task = asyncio.current_task()
        assert task is not None
        stop.cancel_after_grace(task)
        return await coro_factory(stop)  # type: ignore[misc]

    with Interrupts() as stop:
        return asyncio.run(main(stop))


def _child_run(scenario: Scenario, setup: HarnessSetup, index: int, queue, stop_event, parent: int,
               kwargs: dict) -> None:
    """One variant in a forked process; progress and the result (or the exception) go through `queue`."""
    for sig in SIGNAL_NAMES:  # the parent decides; a Ctrl-C reaches the whole process group
        signal.signal(sig, signal.SIG_IGN)

    def progress(done: float, total: float) -> None:
        queue.put(("progress", index, done, total))

    def should_stop() -> str | None:
        if stop_event.is_set():
            return "interrupted"
        if os.getppid() != parent:
            return "the harness process ended"
        return None

    try:
        single = dataclasses.replace(scenario, variants=[scenario.variants[index]])
        plot_dir = kwargs.pop("plot_dir", None)
        runs = asyncio.run(run_variants(single, setup, progress_for=lambda _i: progress,
                                        should_stop=should_stop, **kwargs))
        result = runs[0][0]
        if plot_dir is not None and result.zones and not result.interrupted:  # draw in parallel too
            from .report import slug, write_plot

            path = Path(plot_dir) / f"plot_{slug(result.variant.name)}.png"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_plot(result, path)
            result.plot_path = str(path)
        queue.put(("result", index, runs[0]))
    except BaseException as exc:  # noqa: BLE001 - handed to the parent, which re-raises it
        queue.put(("error", index, exc))


def run_variants_parallel(
    scenario: Scenario,
    setup: HarnessSetup,
    *,
    progress_for: ProgressFor | None = None,
    max_plant_time_s: float | None = None,
    plot_dir: Path | None = None,
) -> list[tuple[RunResult, list[PhaseMetrics]]]:
    """Variants on the embedded stepped soft-PLC, one forked process each. Falls back to sequential runs
    where fork is unavailable. Interrupted: the partial traces the workers handed in."""
    import multiprocessing as mp

    if len(scenario.variants) < 2 or "fork" not in mp.get_all_start_methods():
        return run_async_interruptible(  # type: ignore[return-value]
            lambda stop: run_variants(scenario, setup, progress_for=progress_for,
                                      max_plant_time_s=max_plant_time_s, should_stop=stop)
        )
    setup.program_text()  # bundle and compile once, before forking
    setup.factory_state()
    if plot_dir is not None:  # the workers draw their plots and the parent the comparison: import it once
        from .plots import pyplot

        pyplot()
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    stop_event = ctx.Event()
    kwargs = {"max_plant_time_s": max_plant_time_s, "plot_dir": plot_dir}
    parent = os.getpid()
    procs = [
        ctx.Process(target=_child_run, args=(scenario, setup, i, queue, stop_event, parent, kwargs),
                    daemon=True)
        for i in range(len(scenario.variants))
    ]
    progress: list[ProgressFn | None] = [progress_for(i) if progress_for else None for i in range(len(procs))]
    t0 = time.perf_counter()
    results: dict[int, tuple[RunResult, list[PhaseMetrics]]] = {}
    error: BaseException | None = None
    with Interrupts(on_signal=lambda _reason: stop_event.set()) as stop:
        for p in procs:
            p.start()
        try:
            deadline: float | None = None
            while len(results) < len(procs) and error is None:
                if stop.reason is not None and deadline is None:
                    deadline = time.monotonic() + STOP_GRACE_S
                if deadline is not None and time.monotonic() > deadline:
                    break
                try:
                    kind, index, *payload = queue.get(timeout=POLL_S)
                except queue_mod.Empty:
                    if not any(p.is_alive() for p in procs) and queue.empty():
                        break
                    continue
                if kind == "progress":
                    if progress[index] is not None:
                        progress[index](*payload)  # type: ignore[misc]
                elif kind == "result":
                    results[index] = payload[0]
                else:
                    error = payload[0]
        finally:
            stop_event.set()
            for p in procs:
                p.join(timeout=0.5 if error is None else 0.0)
                if p.is_alive():
                    p.kill()
                    p.join()
    if error is not None:
        raise error
    reason = stop.reason or "the worker process ended without a result"
    for i, variant in enumerate(scenario.variants):
        if i not in results:
            empty = RunResult(scenario=scenario, variant=variant, zones=[], error=reason, interrupted=True)
            results[i] = (empty, [])
        else:
            result = results[i][0]
            if result.interrupted and stop.reason:
                result.error = stop.reason
            if result.interrupted and result.zones:
                results[i] = (result, run_metrics(result))
    if results:
        walls = [r.wall_s for r, _ in results.values()]
        setup.startup_s = max(0.0, time.perf_counter() - t0 - max(walls))
    return [results[i] for i in range(len(procs))]
