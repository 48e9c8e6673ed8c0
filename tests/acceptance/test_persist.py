"""Tuned gains survive a restart of the PLC with OpenPLC's persistent storage on (`thermost plc --persist`):
the soft-PLC keeps %MW/%MD/%ML like OpenPLC's start_pstorage, the application keeps a restored store on
its first scan and takes its defaults only from a blank one. The PLC is killed (no clean stop), so the
values come from the periodic save, as after a power cut."""

from __future__ import annotations

import asyncio
import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from modbus_bridge.client import PlcClient
from modbus_bridge.runner import run_variants
from modbus_bridge.scenario import Variant, load_scenario, resolve_scenario

CLI = "import sys; from plc.cli import main; sys.exit(main())"
PERIOD_S = 0.2


def start_plc(*extra: str) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-c", CLI, "plc", "--port", "0", "--stepped", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = proc.stdout.readline()  # type: ignore[union-attr]
    match = re.search(r":(\d+) ", line)
    if match is None:
        proc.kill()
        pytest.fail(f"the soft-PLC did not start: {line!r}")
    return proc, int(match.group(1))


def read_after_start(harness, port: int, names: list[str]) -> dict:
    async def go():
        async with PlcClient("127.0.0.1", port, harness.regmap) as client:
            await client.step(2)  # the first scans: the application applies its restart rule
            return await client.read_tags(names)

    return asyncio.run(go())


@pytest.fixture
def plcs():
    started: list[subprocess.Popen] = []
    yield started
    for p in started:
        if p.poll() is None:
            p.kill()
            p.wait()


def test_tuned_gains_survive_a_restart_with_persistent_storage(harness, tmp_path, plcs):
    if os.environ.get("THERMOST_PLC"):
        pytest.skip("restarts the embedded soft-PLC; on a real OpenPLC see docs/openplc.md")
    factory = harness.factory_state()
    b = harness.bindings(load_scenario(resolve_scenario("seed003_hotend_fuzzy")))[1]
    gains = [b["kp"], b["tn"]]
    store = tmp_path / "persistent.json"
    persist = ["--persist", str(store), "--persist-period", str(PERIOD_S)]

    plc, port = start_plc(*persist)
    plcs.append(plc)
    sc = load_scenario(resolve_scenario("seed003_hotend_fuzzy"))
    sc = dataclasses.replace(sc, zones=[dataclasses.replace(sc.zones[0], phases=sc.zones[0].phases[:1])],
                             variants=[Variant("tune")])
    ((result, metrics),) = asyncio.run(run_variants(sc, harness, plc=f"127.0.0.1:{port}"))
    assert result.error is None and metrics[0].outcome == "ok", (result.error, metrics[0].outcome)
    tuned = {n: float(v) for n, v in read_after_start(harness, port, gains).items()}
    assert all(abs(tuned[n] - factory.values[n]) > 1e-3 for n in gains), (tuned, "= defaults: not tuned")
    time.sleep(3 * PERIOD_S)  # the periodic save
    plc.send_signal(signal.SIGKILL)
    plc.wait()
    saved = json.loads(store.read_text(encoding="utf-8"))["registers"]
    assert saved[harness.regmap[b["kp"]].location.upper()] != [0, 0]

    plc, port = start_plc(*persist)
    plcs.append(plc)
    after = read_after_start(harness, port, [*gains, b["state"]])
    for n in gains:
        assert after[n] == pytest.approx(tuned[n]), f"{n}: {after[n]} after the restart, tuned {tuned[n]}"
    assert after[b["state"]] == harness.codes.states["IDLE"], "a restart starts IDLE"
    plc.kill()

    plc, port = start_plc("--persist", str(tmp_path / "blank.json"))  # a blank store: the defaults
    plcs.append(plc)
    blank = read_after_start(harness, port, gains)
    for n in gains:
        assert blank[n] == pytest.approx(factory.values[n]), f"{n}: {blank[n]} from a blank store"

    plc, port = start_plc()  # no persistent storage: the defaults, as OpenPLC without start_pstorage
    plcs.append(plc)
    plain = read_after_start(harness, port, gains)
    for n in gains:
        assert plain[n] == pytest.approx(factory.values[n])
