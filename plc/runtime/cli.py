"""`thermost plc [FILE.st] --port N [--stepped] [--persist FILE]`: run the soft-PLC until Ctrl-C / SIGTERM.

Without FILE it runs the bundle (`thermost bundle`: library + application + CONFIGURATION).
The first stdout line is `soft-PLC listening on HOST:PORT ...` (port 0 = ephemeral port).
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal
import sys
from pathlib import Path

from plc.cli import UserError, read_text_file, writable_file
from plc.runtime.engine import ApplicationLike
from plc.runtime.persist import DEFAULT_PERIOD_S, PersistentStore, PersistError
from plc.runtime.server import SoftPlc

NS_PER_MS = 1e6
BUNDLE_NAME = "<thermost bundle>"


LIBRARY_LOGGERS = ("pymodbus", "asyncio")


def configure_logging(verbose: bool = False) -> None:
    """Our own INFO lines; the Modbus library's log lines only with -v."""
    logging.basicConfig(
        level=logging.INFO, stream=sys.stderr, format="thermost plc: %(levelname)s %(message)s"
    )
    for name in LIBRARY_LOGGERS:
        logging.getLogger(name).setLevel(logging.DEBUG if verbose else logging.CRITICAL)


def load_for_cli(file: str | None) -> ApplicationLike:
    """Compile FILE (or the bundle); compile errors become one `file:line:col: message` line each."""
    from plc.st.compiler import load_application
    from plc.st.diagnostics import StError

    if file is None:
        from plc.bundle import bundle_text

        filename, text = BUNDLE_NAME, bundle_text()
    else:
        filename, text = file, read_text_file(file, "ST file", code=True)
    try:
        app = load_application([(filename, text)])
    except StError as exc:
        for diagnostic in getattr(exc, "diagnostics", []):
            sys.stderr.write(f"{diagnostic}\n")
        raise UserError(f"{filename} does not compile") from exc
    if not getattr(app, "programs", True):
        raise UserError(
            f"{filename}: nothing to run: no CONFIGURATION with a PROGRAM instance (OpenPLC needs one)"
        )
    return app


async def _save_periodically(store: PersistentStore) -> None:
    while True:
        await asyncio.sleep(store.period_s)
        store.save_if_changed()


async def serve(
    app: ApplicationLike,
    host: str,
    port: int,
    stepped: bool,
    persist: str | None = None,
    persist_period_s: float = DEFAULT_PERIOD_S,
) -> int:
    try:
        plc = SoftPlc(app, host=host, port=port, stepped=stepped)
    except ValueError as exc:
        raise UserError(str(exc)) from exc
    store: PersistentStore | None = None
    saver: asyncio.Task | None = None
    if persist is not None:
        store = PersistentStore(Path(persist), plc.image, plc.engine.lock, persist_period_s)
        try:
            restored = store.restore()  # before the first scan, as OpenPLC does
        except PersistError as exc:
            raise UserError(str(exc)) from None
        saver = asyncio.create_task(_save_periodically(store))
    loop = asyncio.get_running_loop()
    try:
        await plc.start()
    except OSError as exc:
        raise UserError(str(exc)) from exc
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, plc.stop)
        mode = "stepped (STEP register 60000)" if stepped else "real time"
        kept = ""
        if store is not None:
            kept = f", persistent storage {persist} every {persist_period_s:g} s ({restored} values restored)"
        print(
            f"soft-PLC listening on {host}:{plc.port} ({mode}, interval {app.interval_ns / NS_PER_MS:g} ms, "
            f"{len(plc.image.slots())} located variables served{kept})",
            flush=True,
        )
        await plc.serve_forever()
    finally:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
        if saver is not None:
            saver.cancel()
        await plc.close()
        if store is not None:
            store.save_if_changed()  # a clean stop keeps the last values too
    logging.getLogger("thermost.plc").info("stopped after %d scans", plc.engine.scan_count)
    return 0


def main_plc(args: argparse.Namespace) -> int:
    configure_logging(getattr(args, "verbose", False))
    app = load_for_cli(args.file)
    persist = getattr(args, "persist", None)
    if persist is not None:
        target = Path(persist)
        if target.is_dir():
            raise UserError(f"--persist {persist}: is a directory, expected a file")
        writable_file(persist)
    period = getattr(args, "persist_period", DEFAULT_PERIOD_S)
    return asyncio.run(serve(app, args.host, args.port, args.stepped, persist, period))
