"""Every bad invocation ends in ONE clear line on stderr, exit code 2, no traceback (run in a real
process, as a user types it)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

CLI = "import sys; from plc.cli import main; sys.exit(main())"


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("bad")
    made = {
        "binary": d / "binary.bin",
        "latin1": d / "latin1.st",
        "empty": d / "empty.st",
        "comments": d / "comments.st",
        "library": d / "library.st",
        "emptytoml": d / "empty.toml",
        "unreadable": d / "unreadable.st",
        "existing": d / "existing.txt",
        "dir": d / "folder",
    }
    made["binary"].write_bytes(bytes(range(256)) * 4)
    made["latin1"].write_bytes("(* caf\xe9 *)\nPROGRAM P\nEND_PROGRAM\n".encode("latin-1"))
    made["empty"].write_text("", encoding="utf-8")
    made["comments"].write_text("(* nothing here *)\n// nor here\n", encoding="utf-8")
    made["library"].write_text("FUNCTION_BLOCK FB_A\nVAR n : INT; END_VAR\nn := 1;\nEND_FUNCTION_BLOCK\n")
    made["emptytoml"].write_text("\n", encoding="utf-8")
    made["unreadable"].write_text("PROGRAM P\nEND_PROGRAM\n", encoding="utf-8")
    made["unreadable"].chmod(0)
    made["existing"].write_text("x", encoding="utf-8")
    made["dir"].mkdir()
    return made


CASES = [
    ("run", ["run", "{binary}"]),
    ("run", ["run", "{latin1}"]),
    ("run", ["run", "{emptytoml}"]),
    ("run", ["run", "{dir}"]),
    ("run", ["run", "{unreadable}"]),
    ("run", ["run", "no_such_scenario"]),
    ("run", ["run", "--out", "{existing}"]),
    ("run", ["run", "--out", "{existing}/sub"]),
    ("run", ["run", "--speed", "0"]),
    ("run", ["run", "--speed", "-1"]),
    ("run", ["run", "--speed", "nan"]),
    ("run", ["run", "--speed", "inf"]),
    ("run", ["run", "--plc", "localhost:70000"]),
    ("plc", ["plc", "{binary}"]),
    ("plc", ["plc", "{latin1}"]),
    ("plc", ["plc", "{empty}"]),
    ("plc", ["plc", "{comments}"]),
    ("plc", ["plc", "{library}"]),
    ("plc", ["plc", "{dir}"]),
    ("plc", ["plc", "{unreadable}"]),
    ("plc", ["plc", "--port", "70000"]),
    ("simulate port", ["simulate", "--port", "70000"]),
    ("simulate speed", ["simulate", "--speed", "0"]),
    ("hmi port", ["hmi", "--port", "-1"]),
    ("plc", ["plc", "--port", "-1"]),
    ("plc", ["plc", "--port", "http"]),
    ("plc", ["plc", "--persist", "{dir}"]),
    ("plc", ["plc", "--persist", "{binary}", "--port", "0"]),
    ("plc", ["plc", "--persist", "{existing}", "--port", "0"]),
    ("plc", ["plc", "--persist-period", "0"]),
    ("check", ["check", "{binary}"]),
    ("check", ["check", "{empty}"]),
    ("check", ["check", "{comments}"]),
    ("check", ["check", "{unreadable}"]),
    ("check", ["check", "{dir}"]),  # a folder with no .st files
    ("bundle", ["bundle", "-o", "{dir}"]),
    ("bundle", ["bundle", "-o", "{existing}/x.st"]),
    ("bundle", ["bundle", "-o", "x.st", "--speed", "0"]),
    ("bundle", ["bundle", "-o", "x.st", "--speed", "-1"]),
    ("bundle", ["bundle", "-o", "x.st", "--speed", "2.5"]),
    ("regmap", ["regmap", "-o", "{dir}"]),
    ("none", ["no-such-command"]),
]


@pytest.mark.parametrize(("command", "argv"), CASES, ids=[" ".join(a) for _, a in CASES])
def test_bad_invocation_is_one_line_exit_2(files, tmp_path, command, argv):
    if "{unreadable}" in argv and os.geteuid() == 0:
        pytest.skip("running as root: a mode-0 file is still readable")
    args = [a.format(**files) for a in argv]
    proc = subprocess.run(
        [sys.executable, "-c", CLI, *args], capture_output=True, text=True, timeout=60, cwd=tmp_path
    )
    lines = proc.stderr.strip().splitlines()
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == 2, (proc.returncode, proc.stderr, proc.stdout)
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(("thermost:", str(files["dir"]), str(files["binary"]), str(files["empty"]),
                                str(files["comments"]), str(files["unreadable"]))), lines[0]
    assert not list(tmp_path.glob("x.st")), "nothing is written half-way"
