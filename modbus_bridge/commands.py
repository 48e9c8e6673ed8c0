"""Sub-commands of the harness: `thermost run`, `thermost params`, `thermost scenarios`, `thermost regmap`.

Handlers are imported lazily so `thermost --help` stays fast.
"""

from __future__ import annotations

import argparse

from plc.cli import lazy_handler as _lazy
from plc.cli import port_number, positive_float

from .optimise.cli import add_arguments as _optimise_args
from .scorecard.cli import add_arguments as _scorecard_args


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
    p.add_argument("--format", choices=("csv", "json", "fuxa", "node-red"),
                   help="export with metadata: plain CSV/JSON, FUXA device/tag CSV, Node-RED flow")
    p.add_argument("--plc", default="127.0.0.1:5020", metavar="HOST:PORT",
                   help="PLC address written into the FUXA / Node-RED export (default 127.0.0.1:5020)")
    p.set_defaults(handler=_lazy("modbus_bridge.regmap_export:main_regmap_export"))

    p = sub.add_parser("simulate", help="a scenario's plant in closed loop with the soft-PLC, live")
    p.add_argument("scenario", nargs="?", help="scenario .toml or shipped name (default: t4_tclab, 2 zones)")
    p.add_argument("--port", type=port_number, default=5020,
                   help="Modbus TCP port of the soft-PLC (default 5020)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--speed", type=positive_float, default=1.0, metavar="S",
                   help="plant and PLC run S x real time")
    p.add_argument("--plc", metavar="HOST:PORT", help="run only the plant, against this PLC")
    p.set_defaults(handler=_lazy("modbus_bridge.simulate:main_simulate"))

    p = sub.add_parser("optimise", help="Nelder-Mead search of the PID set over closed-loop experiments")
    _optimise_args(p)
    p.set_defaults(handler=_lazy("modbus_bridge.optimise.cli:main_optimise"))

    p = sub.add_parser("scorecard", help="every controller against the physical bound and the best fixed PID")
    _scorecard_args(p)
    p.set_defaults(handler=_lazy("modbus_bridge.scorecard.cli:main_scorecard"))
