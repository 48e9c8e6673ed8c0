"""Sub-command of the hmi package: `thermost hmi` (the operator panel)."""

from __future__ import annotations

import argparse

from plc.cli import lazy_handler as _lazy
from plc.cli import port_number


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("hmi", help="web operator panel over Modbus TCP (http://127.0.0.1:8080/)")
    p.add_argument("--plc", default="127.0.0.1:5020", metavar="HOST:PORT",
                   help="the PLC (default 127.0.0.1:5020, `thermost simulate`)")
    p.add_argument("--port", type=port_number, default=8080, help="HTTP port of the panel (default 8080)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--data", default="data", metavar="DIR",
                   help="data folder: hmi.sqlite (history, alarms, audit), hmi-access.toml (default data/)")
    p.add_argument("--rate", type=float, default=10.0, metavar="HZ", help="poll rate (default 10 Hz)")
    p.add_argument("--hash-password", action="store_true",
                   help="read a password (stdin) and print its hash for hmi-access.toml")
    p.set_defaults(handler=_lazy("hmi.cli:main_hmi"))
