"""The soft-PLC's scan results stay bit-identical: a 2,000-scan closed loop of a frozen copy of the
bundle (tests/st/bundle_reference.st, made once with `thermost bundle`) against the seed 003 hot-end
FOPDT, zone 1 self-tuning then ACTIVE with the fuzzy adapter on. Every located variable is packed
into raw bytes after every scan and the whole trace is hashed; the expected digest was recorded from
the compiler before it was split into stages, so any change in the generated arithmetic shows here.

The reference file is frozen on purpose: changes to the application program do not move the digest,
only changes to how the soft-PLC compiles and runs ST do.
"""

from __future__ import annotations

import hashlib
import struct
from pathlib import Path

from modbus_bridge.plants.base import PlantDisturbance
from modbus_bridge.plants.linear import Fopdt
from plc.st.compiler import load_application

REFERENCE = Path(__file__).parent / "st" / "bundle_reference.st"
SCANS = 2000
TUNE_SCANS = 1200  # then ACTIVE with the gains the tuner left (or the defaults if it did not finish)
MODE_ACTIVE = 2
MODE_TUNE = 5
SETPOINT_C = 40.0
# seed 003 hot end: G(s) = 0.232 e^(-10.6 s) / (23.4 s + 1)
PLANT_GAIN = 0.232
PLANT_T_S = 23.4
PLANT_L_S = 10.6
EXPECTED_SHA256 = "5e9eac4d85c6a7caa640c25a0a2bdde36948be9be5bca1bda5630e324e4895fa"


def _pack(iec_type: str, value: object) -> bytes:
    if isinstance(value, bool):
        return struct.pack("<?", value)
    if isinstance(value, float):
        return struct.pack("<d", value)  # the exact Python float, stricter than the REAL's 4 bytes
    if isinstance(value, int):
        return struct.pack("<q", value)
    raise AssertionError(f"located variable of type {iec_type} holds {type(value).__name__}")


def run_trace() -> tuple[str, dict[str, object]]:
    app = load_application([(REFERENCE.name, REFERENCE.read_text(encoding="utf-8"))])
    tags = {lv.name: lv for lv in app.located}
    dt = app.interval_ns / 1e9
    plant = Fopdt(gain_c_per_pct=PLANT_GAIN, time_constant_s=PLANT_T_S, dead_time_s=PLANT_L_S)
    dist = PlantDisturbance.for_channels(1)
    tags["fSetpointZone1"].set(SETPOINT_C)
    tags["bFuzzyZone1"].set(True)
    tags["nModeZone1"].set(MODE_TUNE)
    digest = hashlib.sha256()
    for scan in range(SCANS):
        if scan == TUNE_SCANS:
            tags["nModeZone1"].set(MODE_ACTIVE)
        tags["fPvZone1"].set(plant.temperatures()[0])
        app.scan()
        for lv in app.located:
            digest.update(_pack(lv.iec_type, lv.get()))
        plant.step([max(0.0, tags["fYZone1"].get())], dt, dist)
    final = {name: tags[name].get() for name in ("nStateZone1", "fPvZone1", "fYZone1", "fKpZone1")}
    return digest.hexdigest(), final


def test_closed_loop_trace_of_the_reference_bundle_is_bit_identical():
    digest, final = run_trace()
    # the run does something: the loop is closed and the controller is in ACTIVE with tuned gains
    assert final["nStateZone1"] == MODE_ACTIVE, final
    assert final["fPvZone1"] > 30.0, final
    assert digest == EXPECTED_SHA256, final
