"""Start the panel: register map -> model, SQLite store, access levels, Modbus poller, NiceGUI pages.

NiceGUI serves FastAPI + Vue/Quasar + ECharts from the installed package (no CDN) and runs its pages on
the same asyncio loop as the pymodbus poller. It binds 127.0.0.1 unless a host is given.
"""

from __future__ import annotations

import os
import secrets
from dataclasses import dataclass
from pathlib import Path

STATIC_DIR = Path(__file__).resolve().parent / "static"


@dataclass
class HmiOptions:
    plc_host: str = "127.0.0.1"
    plc_port: int = 5020
    host: str = "127.0.0.1"
    port: int = 8080
    data_dir: Path = Path("data")
    rate_hz: float = 10.0


def check_port_free(host: str, port: int) -> None:
    """Raise OSError with a clear reason when the panel's address cannot be bound (before NiceGUI starts)."""
    import socket

    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((host, port))


def run(opts: HmiOptions) -> None:
    import logging

    check_port_free(opts.host, opts.port)
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)  # the panel shows the connection state itself
    os.environ.setdefault("NICEGUI_STORAGE_PATH", str((opts.data_dir / "nicegui").resolve()))
    from nicegui import app, ui

    from modbus_bridge.regmap import load_register_map

    from . import layout, pages_eng, pages_live, pages_more  # noqa: F401  (the modules register the pages)
    from .auth import Access
    from .model import load_model
    from .poller import Poller
    from .store import Store

    model = load_model(load_register_map())
    store = Store(opts.data_dir)
    access = Access.load(opts.data_dir)
    poller = Poller(model, opts.plc_host, opts.plc_port, rate_hz=opts.rate_hz, store=store)
    layout.PANEL = layout.Panel(model, poller, store, access, f"{opts.plc_host}:{opts.plc_port}")
    app.add_static_files("/hmi-static", STATIC_DIR)
    app.on_startup(poller.start)

    async def shutdown() -> None:
        await poller.stop()
        store.close()

    app.on_shutdown(shutdown)
    print(f"thermost hmi: http://{opts.host}:{opts.port}/ (PLC {opts.plc_host}:{opts.plc_port}, "
          f"data {opts.data_dir}, engineer level {'on' if access.engineer_enabled() else 'off'})",
          flush=True)
    ui.run(host=opts.host, port=opts.port, reload=False, show=False, title="ThermoST panel",
           storage_secret=secrets.token_hex(16), show_welcome_message=False, favicon="🌡",
           uvicorn_logging_level="warning")
