"""`thermost hmi [--plc HOST:PORT] [--port 8080] [--host 127.0.0.1] [--data DIR]`."""

from __future__ import annotations

import argparse
import getpass
import math
import sys
from pathlib import Path

from plc.cli import UserError


def main_hmi(args: argparse.Namespace) -> int:
    from modbus_bridge.runner import parse_host_port

    from .auth import AccessConfigError, hash_password

    if args.hash_password:
        pw = getpass.getpass("password: ") if sys.stdin.isatty() else sys.stdin.readline().rstrip("\n")
        if not pw:
            raise UserError("empty password")
        print(hash_password(pw))
        return 0
    try:
        host, port = parse_host_port(args.plc)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    if not 0 < args.port < 65536:
        raise UserError(f"--port must be 1..65535, not {args.port}")
    if not (math.isfinite(args.rate) and 0.5 <= args.rate <= 50):
        raise UserError(f"--rate must be 0.5 .. 50 Hz, not {args.rate}")
    from .app import HmiOptions, run

    try:
        run(HmiOptions(plc_host=host, plc_port=port, host=args.host, port=args.port,
                       data_dir=Path(args.data), rate_hz=args.rate))
    except AccessConfigError as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:
        raise UserError(f"cannot serve the panel on {args.host}:{args.port}: {exc.strerror or exc}") from None
    return 0
