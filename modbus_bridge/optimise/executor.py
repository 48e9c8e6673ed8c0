"""One executor for sweeps and optimiser evaluations.

- `LocalExecutor` (default): a process pool on this machine (fork where available, so every worker
  inherits the bundled program); every evaluation loads its own embedded soft-PLC.
- `DaskExecutor` (`--scheduler ADDRESS`): the same functions on a Dask distributed cluster, so a sweep of
  thousands of plant variants can leave one machine (the workers need this package installed).
- `SerialExecutor`: in this process, one after the other (an external `--plc`: one PLC, one experiment
  at a time).

`map(fn, items, progress)` returns the results in the order of `items`; `progress(done, total)` is
called as results arrive. `fn` must be a module-level function and the items picklable.
"""

from __future__ import annotations

import multiprocessing as mp
import os
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Protocol

Progress = Callable[[int, int], None]


class ExecutorError(RuntimeError):
    """The executor cannot be set up (e.g. no Dask scheduler at that address)."""


class Executor(Protocol):
    name: str
    workers: int

    def map(
        self, fn: Callable[[Any], Any], items: Sequence[Any], progress: Progress | None = None
    ) -> list: ...

    def close(self) -> None: ...


class SerialExecutor:
    def __init__(self) -> None:
        self.name, self.workers = "serial", 1

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any], progress: Progress | None = None) -> list:
        out = []
        for i, item in enumerate(items):
            out.append(fn(item))
            if progress is not None:
                progress(i + 1, len(items))
        return out

    def close(self) -> None:
        pass

    def __enter__(self) -> SerialExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _gather(futures: list[Future], progress: Progress | None) -> list:
    pending = set(futures)
    done_count = 0
    while pending:
        done, pending = wait(pending, return_when=FIRST_COMPLETED)
        done_count += len(done)
        if progress is not None:
            progress(done_count, len(futures))
    return [f.result() for f in futures]


class LocalExecutor:
    def __init__(self, workers: int | None = None) -> None:
        self.workers = max(1, workers or os.cpu_count() or 1)
        self.name = f"local processes ({self.workers})"
        method = "fork" if "fork" in mp.get_all_start_methods() else None
        self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context(method))

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any], progress: Progress | None = None) -> list:
        return _gather([self._pool.submit(fn, item) for item in items], progress)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> LocalExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class DaskExecutor:
    def __init__(self, address: str, timeout_s: float = 5.0) -> None:
        try:
            from distributed import Client
        except ImportError as exc:
            raise ExecutorError(
                "--scheduler needs the 'distributed' package (pip install 'thermost[dask]')"
            ) from exc
        try:
            self._client = Client(address, timeout=timeout_s)
        except (OSError, TimeoutError, ValueError) as exc:
            raise ExecutorError(f"no Dask scheduler at {address}: {exc}") from None
        info = self._client.scheduler_info()
        self.workers = max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))
        self.name = f"dask {address} ({self.workers} worker threads)"

    def map(self, fn: Callable[[Any], Any], items: Sequence[Any], progress: Progress | None = None) -> list:
        from distributed import as_completed

        futures = self._client.map(fn, list(items), pure=False)
        for n, _ in enumerate(as_completed(futures), start=1):
            if progress is not None:
                progress(n, len(futures))
        return self._client.gather(futures)

    def close(self) -> None:
        self._client.close()

    def __enter__(self) -> DaskExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def make_executor(scheduler: str | None = None, workers: int | None = None, serial: bool = False) -> Executor:
    if serial:
        return SerialExecutor()
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers)
