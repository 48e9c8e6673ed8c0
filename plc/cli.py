"""`thermost` command line: one entry point, sub-commands registered by each package.

Each package owns a `commands` module with `register(subparsers)`; a sub-command's
handler returns an exit code. Errors a user can cause end in one clear line on stderr.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import re
import sys
from pathlib import Path

COMMAND_MODULES = ("plc.commands", "modbus_bridge.commands", "hmi.commands")


def lazy_handler(target: str):
    """Handler for "module:function", imported only when the sub-command runs."""
    module_name, func_name = target.split(":")

    def handler(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module_name), func_name)(args)

    return handler


class UserError(Exception):
    """An error caused by the user's input: printed as one line, exit code 2."""


MAX_PORT = 65535
_ST_COMMENT = re.compile(r"\(\*.*?\*\)|//[^\n]*", re.DOTALL)


def read_text_file(name: str, what: str = "file", *, code: bool = False) -> str:
    """The UTF-8 text of a user-given file, or UserError with one line: missing, a directory, unreadable,
    binary, not UTF-8, empty (code=True: nothing but comments counts as empty too)."""
    path = Path(name)
    if not path.exists():
        raise UserError(f"{name}: no such {what}")
    if path.is_dir():
        raise UserError(f"{name}: is a directory, expected a {what}")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise UserError(f"{name}: cannot read: {exc.strerror or exc}") from None
    if b"\0" in raw:
        raise UserError(f"{name}: binary data, expected a text {what}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UserError(f"{name}: not UTF-8 text (byte {exc.start}), expected a text {what}") from None
    body = _ST_COMMENT.sub("", text) if code else text
    if not body.strip():
        raise UserError(f"{name}: empty {what}" + (" (nothing but comments)" if text.strip() else ""))
    return text


def writable_file(name: str) -> Path:
    """An output file path that can be written: not a directory, its folder creatable and writable."""
    path = Path(name)
    if path.is_dir() or name.endswith(("/", os.sep)):
        raise UserError(f"{name}: is a directory, expected an output file name")
    folder = path.parent
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise UserError(f"{name}: {existing} is not a directory")
    if not os.access(existing, os.W_OK):
        raise UserError(f"{name}: {existing} is not writable")
    return path


def port_number(text: str) -> int:
    """argparse type: a TCP port 0..65535 (0 = any free port)."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"port must be a whole number, not {text!r}") from None
    if not 0 <= port <= MAX_PORT:
        raise argparse.ArgumentTypeError(f"port must be 0..{MAX_PORT}, not {port}")
    return port


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, not {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, not {text}")
    return value


def positive_int(text: str) -> int:
    """argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, not {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, not {value}")
    return value


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
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage error (one line already written) or --help
        return exc.code if isinstance(exc.code, int) else 2
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
