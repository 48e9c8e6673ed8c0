"""`thermost` command line: one entry point, sub-commands registered by each package.

Each package owns a `commands` module with `register(subparsers)`; a sub-command's
handler returns an exit code. Errors a user can cause end in one clear line on stderr.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

COMMAND_MODULES = ("plc.commands", "modbus_bridge.commands", "hmi.commands")


def lazy_handler(target: str):
    """Handler for "module:function", imported only when the sub-command runs."""
    module_name, func_name = target.split(":")

    def handler(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module_name), func_name)(args)

    return handler


class UserError(Exception):
    """An error caused by the user's input: printed as one line, exit code 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one clear line instead of usage + message
        sys.stderr.write(f"thermost: {message} (see 'thermost --help')\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="thermost", description="ThermoST: ST temperature control, soft-PLC and Modbus harness"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "handler", None):
        parser.print_help()
        return 2
    try:
        return int(args.handler(args) or 0)
    except UserError as exc:
        sys.stderr.write(f"thermost: {exc}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("thermost: interrupted\n")
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    # run through the package module so UserError is the same class the sub-commands raise
    from plc.cli import main as _main

    raise SystemExit(_main())
