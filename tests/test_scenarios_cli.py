"""`thermost run / scenarios / regmap` from the command line: bad input is one clear line."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from modbus_bridge.regmap import APP_DIR, load_register_map, markdown
from modbus_bridge.scenario import shipped_scenarios
from plc.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_scenarios_lists_every_shipped_file(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for p in shipped_scenarios():
        assert p.stem in out
    assert "INVALID" not in out


def test_bad_scenario_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    good = (ROOT / "tests" / "harness_fixtures" / "small_fopdt.toml").read_text(encoding="utf-8")
    bad.write_text("warp = 9\n" + good, encoding="utf-8")
    assert main(["run", str(bad), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and str(bad) in err and "warp" in err and "unknown key" in err


def test_bad_plc_address_and_speed(capsys):
    assert main(["run", "--plc", "nohost", "--quiet"]) == 2
    assert "HOST:PORT" in capsys.readouterr().err
    assert main(["run", "--speed", "0", "--quiet"]) == 2
    assert "--speed" in capsys.readouterr().err
    assert main(["run", "--realtime", "--speed", "10", "--quiet"]) == 2
    assert "TASK interval" in capsys.readouterr().err


@pytest.mark.skipif(not list(APP_DIR.glob("*.st")), reason="no application in plc/app yet")
def test_regmap_markdown_matches_the_generator(tmp_path):
    out = tmp_path / "map.md"
    assert main(["regmap", "--markdown", "-o", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == markdown(load_register_map())


@pytest.mark.skipif(not list(APP_DIR.glob("*.st")), reason="no application in plc/app yet")
def test_run_against_an_external_stepped_plc(tmp_path):
    """`thermost plc --stepped` in another process, `thermost run --plc` against it."""
    thermost = [sys.executable, "-c", "import sys; from plc.cli import main; sys.exit(main(sys.argv[1:]))"]
    plc = subprocess.Popen(
        [*thermost, "plc", "--port", "0", "--stepped"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = plc.stdout.readline()
        if "listening on" not in line:
            pytest.skip(f"`thermost plc` did not start: {line!r} {plc.stderr.read() if plc.poll() else ''}")
        address = line.split("listening on ", 1)[1].split()[0]
        out = tmp_path / "rep"
        run = subprocess.run(
            [*thermost, "run", "seed003_sensor_fault", "--plc", address, "--out", str(out), "--quiet"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stderr
        doc = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
        phases = doc["variants"][0]["phases"]
        assert phases[0]["phase"] == "tune" and phases[0]["outcome"] == "ok"
        assert "stepped" in run.stdout
    finally:
        os.kill(plc.pid, signal.SIGINT)
        plc.wait(timeout=10)


def test_unreachable_plc_is_one_line(capsys):
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    assert main(["run", "seed003_sensor_fault", "--plc", f"127.0.0.1:{port}", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cannot connect" in err


@pytest.mark.skipif(not list(APP_DIR.glob("*.st")), reason="no application in plc/app yet")
def test_two_plcs_run_two_variants_side_by_side(tmp_path, capsys):
    from plc.bundle import bundle_text
    from plc.runtime.server import SoftPlcThread

    text = (ROOT / "modbus_bridge" / "scenarios" / "seed003_sensor_fault.toml").read_text(encoding="utf-8")
    text += '\n[[variant]]\nname = "left"\n\n[[variant]]\nname = "right"\n'
    scenario = tmp_path / "two.toml"
    scenario.write_text(text, encoding="utf-8")
    program = bundle_text()
    with SoftPlcThread(program, "127.0.0.1", 0, True) as a, SoftPlcThread(program, "127.0.0.1", 0, True) as b:
        rc = main(
            [
                "run",
                str(scenario),
                "--plc",
                f"127.0.0.1:{a.port}",
                "--plc",
                f"127.0.0.1:{b.port}",
                "--out",
                str(tmp_path / "out"),
                "--quiet",
            ]
        )
    assert rc == 0, capsys.readouterr().err
    doc = json.loads((tmp_path / "out" / "metrics.json").read_text(encoding="utf-8"))
    left, right = doc["variants"]
    assert (left["name"], right["name"]) == ("left", "right")
    assert left["phases"] == right["phases"]  # same scenario, same seed, two stepped PLCs: same result
    assert (
        main(["run", str(scenario), "--plc", "127.0.0.1:1", "--plc", "127.0.0.1:2", "--plc", "127.0.0.1:3"])
        == 2
    )
    assert "3 PLCs for 2 variant(s)" in capsys.readouterr().err
