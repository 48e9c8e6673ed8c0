"""Sub-commands of the harness: `thermost run`, `thermost params`, `thermost scenarios`, `thermost regmap`.

Handlers are imported lazily so `thermost --help` stays fast.
"""

from __future__ import annotations

import argparse

from plc.cli import lazy_handler as _lazy
from plc.cli import positive_float


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a scenario against the embedded soft-PLC (default) or a PLC")
    p.add_argument(
        "scenario", nargs="?", help="scenario .toml file or shipped name (default: seed 003 hot end)"
    )
    p.add_argument(
        "--plc",
        metavar="HOST:PORT",
        action="append",
        help="use this PLC (OpenPLC or `thermost plc`) instead; repeat it to run variant i on PLC i "
        "at the same time",
    )
    p.add_argument("--realtime", action="store_true", help="embedded soft-PLC on its real-time clock")
    p.add_argument(
        "--speed",
        type=positive_float,
        default=1.0,
        metavar="N",
        help="real time only: plant runs N x faster than the wall clock (shorten the TASK interval)",
    )
    p.add_argument("--out", metavar="DIR", help="report directory (default out/<scenario>)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("-v", "--verbose", action="store_true", help="log lines of the Modbus library too")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_run"))

    p = sub.add_parser("params", help="save a PLC's parameter set to a file, or load it back")
    p.add_argument("action", choices=("save", "load"))
    p.add_argument("file", metavar="FILE", help="JSON parameter file")
    p.add_argument("--plc", metavar="HOST:PORT", required=True, help="the PLC (OpenPLC or `thermost plc`)")
    p.set_defaults(handler=_lazy("modbus_bridge.params:main_params"))

    p = sub.add_parser("scenarios", help="list the shipped scenarios, or the JSON Schema of the format")
    p.add_argument("--schema", action="store_true", help="print the JSON Schema of scenario files instead")
    p.add_argument("-o", "--output", metavar="FILE", help="with --schema: write to FILE")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_scenarios"))

    p = sub.add_parser("docs", help="rewrite the generated figure blocks of docs/*.md (make docs)")
    p.add_argument("--check", action="store_true", help="only report stale blocks (exit 1), write nothing")
    p.add_argument("--only", action="append", metavar="NAME", help="only this producer (repeatable)")
    p.add_argument("--skip-measured", action="store_true", help="leave machine-dependent timings alone")
    p.set_defaults(handler=_lazy("modbus_bridge.docfigures:main_docs"))

    p = sub.add_parser("regmap", help="print the Modbus register map derived from the application")
    p.add_argument("--markdown", action="store_true", help="markdown (docs/register-map.md)")
    p.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_regmap"))
