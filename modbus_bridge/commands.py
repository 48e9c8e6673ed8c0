"""Sub-commands of the harness: `thermost run`, `thermost scenarios`, `thermost regmap`.

Handlers are imported lazily so `thermost --help` stays fast.
"""

from __future__ import annotations

import argparse

from plc.cli import lazy_handler as _lazy

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
        type=float,
        default=1.0,
        metavar="N",
        help="real time only: plant runs N x faster than the wall clock (shorten the TASK interval)",
    )
    p.add_argument("--out", metavar="DIR", help="report directory (default out/<scenario>)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_run"))

    p = sub.add_parser("scenarios", help="list the shipped scenarios")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_scenarios"))

    p = sub.add_parser("regmap", help="print the Modbus register map derived from the application")
    p.add_argument("--markdown", action="store_true", help="markdown (docs/register-map.md)")
    p.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    p.set_defaults(handler=_lazy("modbus_bridge.cli:main_regmap"))

    p = sub.add_parser("optimise", help="Nelder-Mead search of the PID set over closed-loop experiments")
    _optimise_args(p)
    p.set_defaults(handler=_lazy("modbus_bridge.optimise.cli:main_optimise"))

    p = sub.add_parser("scorecard", help="every controller against the physical bound and the best fixed PID")
    _scorecard_args(p)
    p.set_defaults(handler=_lazy("modbus_bridge.scorecard.cli:main_scorecard"))
