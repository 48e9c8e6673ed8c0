"""Acceptance suite: Modbus-driven checks of the library's promises through the harness.

Runs against the embedded soft-PLC (stepped) by default, or against the PLC at THERMOST_PLC=HOST:PORT
(an OpenPLC runtime or `thermost plc --stepped`) running the project's bundle. Every test here carries
the `acceptance` marker; a missing piece of the project makes a test skip with the reason printed.
"""

from __future__ import annotations

import asyncio
import os

import numpy as np
import pytest

from modbus_bridge.alarms import describe
from modbus_bridge.binding import ControllerCodes, resolve_zone
from modbus_bridge.loop import RunResult
from modbus_bridge.regmap import APP_DIR, RegisterMapError
from modbus_bridge.runner import HarnessSetup, run_variants
from modbus_bridge.scenario import Scenario

PLC_ENV = "THERMOST_PLC"
STATE_ERROR = ControllerCodes.load().states["ERROR"]
SPEED_ENV = "THERMOST_PLC_SPEED"


def pytest_collection_modifyitems(items):
    for item in items:
        if "tests/acceptance" in str(item.fspath).replace("\\", "/"):
            item.add_marker(pytest.mark.acceptance)


@pytest.fixture(scope="session")
def harness() -> HarnessSetup:
    if not list(APP_DIR.glob("*.st")):
        pytest.skip(f"the application (plc/app/*.st) is missing: nothing to test through Modbus in {APP_DIR}")
    try:
        setup = HarnessSetup.default()
        resolve_zone(setup.regmap, 1)
    except RegisterMapError as exc:
        pytest.skip(f"the application's register map is not usable by the harness: {exc}")
    if os.environ.get(PLC_ENV) is None:
        try:
            from plc.runtime.server import SoftPlc  # noqa: F401
        except ImportError as exc:
            pytest.skip(f"the embedded soft-PLC is missing ({exc}) and {PLC_ENV} is not set")
    return setup


def run_scenario(setup: HarnessSetup, scenario: Scenario):
    """Run every variant of the scenario on the configured PLC; returns [(RunResult, [PhaseMetrics])]."""
    return asyncio.run(run_variants(scenario, setup, plc=os.environ.get(PLC_ENV), speed=plc_speed()))


def plc_speed() -> float:
    """THERMOST_PLC_SPEED=N when the real PLC runs a bundle made with `thermost bundle --speed N`."""
    raw = os.environ.get(SPEED_ENV, "1")
    try:
        speed = float(raw)
    except ValueError:
        raise pytest.UsageError(f"{SPEED_ENV}={raw!r} is not a number") from None
    if speed <= 0:
        raise pytest.UsageError(f"{SPEED_ENV} must be > 0")
    return speed


def alarm_word(alarms) -> int:
    """Every alarm bit a trace ever showed."""
    return int(np.bitwise_or.reduce(np.asarray(alarms, dtype=np.int64))) if len(alarms) else 0


def assert_no_alarm(result: RunResult, label: str) -> None:
    """No alarm bit and no ERROR state in any zone of the run."""
    assert result.error is None, result.error
    for zone in result.zones:
        word = alarm_word(zone.alarm)
        assert word == 0, f"{label} / {zone.name}: {describe(word)}"
        assert STATE_ERROR not in zone.state, f"{label} / {zone.name}: state ERROR"
