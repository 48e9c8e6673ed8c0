"""A long-running PLC, as a real OpenPLC is: the sensor-fault scenarios one after another on ONE soft-PLC.
Each run must start from the known state the harness restores (reset.py), whatever the run before left:
a faulty PV, latched alarms, tuned gains, a changed parameter."""

from __future__ import annotations

import asyncio

import pytest

from modbus_bridge.client import PlcClient
from modbus_bridge.reset import reset_to_known_state
from modbus_bridge.runner import run_variants

from .test_acceptance import assert_sensor_fault_handled, sensor_fault_scenario


@pytest.fixture(scope="module")
def one_plc(harness):
    from plc.runtime.server import SoftPlcThread

    with SoftPlcThread(harness.program_text(), stepped=True) as plc:
        yield f"127.0.0.1:{plc.port}"


@pytest.mark.parametrize("fault", ["open", "short", "short"])
def test_sensor_faults_back_to_back_on_one_plc(harness, one_plc, fault):
    ((result, _),) = asyncio.run(run_variants(sensor_fault_scenario(fault), harness, plc=one_plc))
    assert_sensor_fault_handled(result, fault)


def test_reset_restores_parameters_and_clears_alarms(harness, one_plc):
    """A parameter changed and a faulty PV left behind: the reset restores both and reads them back."""
    sc = sensor_fault_scenario("open")
    bindings = harness.bindings(sc)
    b = bindings[1]
    factory = harness.factory_state()

    async def go():
        host, port = one_plc.split(":")
        async with PlcClient(host, int(port), harness.regmap) as client:
            active = harness.codes.modes["ACTIVE"]
            await client.step(1)  # a PLC fresh from its start sets its registers in its first scan
            await client.write_tags({b["kp"]: 99.0, b["pv"]: -300.0, b["mode"]: active})
            await client.step(5)
            dirty = await client.read_tags([b["kp"], b["alarm"]])
            await reset_to_known_state(client, sc, bindings, harness.codes, factory, stepped=True)
            return dirty, await client.read_tags([b["kp"], b["alarm"], b["pv"], b["state"]])

    dirty, clean = asyncio.run(go())
    assert dirty[b["kp"]] == 99.0 and dirty[b["alarm"]] != 0, dirty  # the PLC really was left dirty
    assert clean[b["kp"]] == pytest.approx(factory.values[b["kp"]])
    assert clean[b["alarm"]] == 0
    assert clean[b["state"]] == harness.codes.states["RESET"]
    assert clean[b["pv"]] == pytest.approx(sc.build_plant().temperatures()[0])
