"""Sub-commands of the plc package: check, plc, bundle, bench.

Handlers are imported lazily so `thermost --help` stays fast and one broken
module does not take the whole CLI down.
"""

from __future__ import annotations

import argparse

from plc.cli import lazy_handler as _lazy
from plc.cli import port_number, positive_float, positive_int


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="MatIEC-strict check of .st files (file:line:col: message)")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.set_defaults(handler=_lazy("plc.checker:main_check"))

    p = sub.add_parser("plc", help="run the embedded soft-PLC with OpenPLC's Modbus TCP map")
    p.add_argument("file", nargs="?", help=".st file (default: the bundled library + application)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--port", type=port_number, default=5020, help="Modbus TCP port (default 5020; 0: any)")
    p.add_argument("--stepped", action="store_true", help="PLC time advances only when a client asks")
    p.add_argument("-v", "--verbose", action="store_true", help="log lines of the Modbus library too")
    p.add_argument("--persist", metavar="FILE",
                   help="OpenPLC's persistent storage: keep %%MW/%%MD/%%ML in FILE across restarts")
    p.add_argument("--persist-period", type=positive_float, default=10.0, metavar="S",
                   help="save the store every S seconds when a kept value changed (default 10, as OpenPLC)")
    p.set_defaults(handler=_lazy("plc.runtime.cli:main_plc"))

    p = sub.add_parser("bundle", help="write the single .st file to upload to OpenPLC")
    p.add_argument("-o", "--output", required=True, metavar="FILE")
    p.add_argument("--speed", type=positive_int, default=1, metavar="N",
                   help="divide the TASK interval by N (controllers keep their cycle time: the plant of a "
                        "real-time harness runs N x faster, e.g. `thermost run --plc H:P --speed N`)")
    p.set_defaults(handler=_lazy("plc.bundle:main_bundle"))

    p = sub.add_parser("bench", help="print soft-PLC, adapter and harness benchmark figures")
    p.add_argument("--quick", action="store_true", help="fewer repetitions")
    p.set_defaults(handler=_lazy("plc.bench:main_bench"))
