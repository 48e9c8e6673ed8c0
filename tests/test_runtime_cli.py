"""`thermost plc` as a process: compiled ST programs, SIGINT, faults, bit-for-bit determinism,
and the pid_plant conformance case read over Modbus against the recorded OpenPLC words."""

from __future__ import annotations

import json
import re
import signal
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from plc.bench import CLI_SNIPPET, conformance_dir
from plc.runtime import control
from plc.runtime.rawclient import ModbusException, RawModbusClient
from plc.runtime.server import SoftPlcThread

ROOT = Path(__file__).resolve().parents[1]
START_TIMEOUT_S = 60
STOP_TIMEOUT_S = 10

FAULT_PROGRAM = """
PROGRAM P_Fault
  VAR
    divisor AT %MW0 : INT := 1;
    idx AT %MW1 : INT := 1;
    res AT %MW2 : INT;
    cnt AT %MD0 : DINT;
    arr : ARRAY[1..4] OF INT;
  END_VAR
  cnt := cnt + 1;
  res := 100 / divisor;
  arr[idx] := res;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK task0(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst0 WITH task0 : P_Fault;
  END_RESOURCE
END_CONFIGURATION
"""

LOOP_PROGRAM = """
PROGRAM P_Loop
  VAR
    pv AT %MD0 : REAL;
    u AT %MD1 : REAL;
    integ AT %MD2 : REAL;
    t_on AT %MD3 : DINT;
    big AT %ML0 : LREAL;
    hot AT %QX0.0 : BOOL;
    timer : TON;
    e : REAL;
  END_VAR
  e := 50.0 - pv;
  integ := LIMIT(-100.0, integ + 0.37 * e * 0.01, 100.0);
  u := 1.3 * e + integ;
  big := big + REAL_TO_LREAL(u) * 0.1;
  timer(IN := pv > 40.0, PT := T#250ms);
  hot := timer.Q;
  t_on := TIME_TO_DINT(timer.ET * 1000);
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK task0(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst0 WITH task0 : P_Loop;
  END_RESOURCE
END_CONFIGURATION
"""


class PlcProcess:
    """`thermost plc FILE --port 0` in a subprocess; the port comes from its first stdout line."""

    def __init__(self, args: list[str]):
        self.proc = subprocess.Popen(
            [sys.executable, "-c", CLI_SNIPPET, "plc", *args, "--port", "0"],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        line = self.proc.stdout.readline() if self.proc.stdout else ""
        match = re.search(r"listening on 127\.0\.0\.1:(\d+)", line)
        if not match:
            self.proc.kill()
            _, err = self.proc.communicate(timeout=STOP_TIMEOUT_S)
            raise AssertionError(f"soft-PLC did not start: {line!r} {err}")
        self.port = int(match.group(1))

    def interrupt(self) -> tuple[int, str]:
        self.proc.send_signal(signal.SIGINT)
        _, err = self.proc.communicate(timeout=STOP_TIMEOUT_S)
        return self.proc.returncode, err

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate(timeout=STOP_TIMEOUT_S)


def real_words(value: float) -> list[int]:
    return list(struct.unpack(">HH", struct.pack(">f", value)))


def drive_loop(port: int, n_steps: int) -> list[int]:
    """Stepped closed loop: PV from a first-order plant computed here; every output word kept."""
    trace: list[int] = []
    pv = 20.0
    with RawModbusClient("127.0.0.1", port) as client:
        client.set_rw_steps(1)
        for _ in range(n_steps):
            out = client.read_write(2048, 8, 2048, real_words(pv))
            u = struct.unpack(">f", struct.pack(">HH", *out[2:4]))[0]
            pv = pv + (u - pv) * 0.02
            trace += out + client.read_holding(4096, 4) + [int(client.read_coils(0, 1)[0])]
        status = client.status()
        trace += [status.scan_count, status.time_ms]
    return trace


def test_sigint_stops_cleanly_and_real_time_runs(tmp_path):
    source = tmp_path / "loop.st"
    source.write_text(LOOP_PROGRAM)
    plc = PlcProcess([str(source)])
    try:
        with RawModbusClient("127.0.0.1", plc.port) as client:
            assert client.status().mode == control.MODE_REALTIME
    finally:
        code, err = plc.interrupt()
    assert code == 0, err
    assert "Traceback" not in err and "stopped after" in err


def test_stepped_runs_are_identical_bit_for_bit(tmp_path):
    source = tmp_path / "loop.st"
    source.write_text(LOOP_PROGRAM)
    traces = []
    for _ in range(2):
        plc = PlcProcess([str(source), "--stepped"])
        try:
            traces.append(drive_loop(plc.port, 300))
        finally:
            assert plc.interrupt()[0] == 0
    with SoftPlcThread(Path(source), stepped=True) as in_process:
        traces.append(drive_loop(in_process.port, 300))
    assert traces[0] == traces[1] == traces[2]
    assert traces[0][-2:] == [300, 300 * 10]  # one scan per FC23; 10 ms of PLC time per scan
    assert any(traces[0][i] for i in range(len(traces[0]) - 2))


def test_compile_error_is_one_line_per_diagnostic(tmp_path):
    source = tmp_path / "bad.st"
    source.write_text("PROGRAM P\n  VAR x : INT; END_VAR\n  x := ;\nEND_PROGRAM\n")
    proc = subprocess.run([sys.executable, "-c", CLI_SNIPPET, "plc", str(source), "--port", "0"], cwd=ROOT,
                          capture_output=True, text=True, timeout=START_TIMEOUT_S)
    assert proc.returncode == 2
    assert re.search(r"bad\.st:\d+:\d+: ", proc.stderr)


def test_runtime_faults_of_a_compiled_program():
    with SoftPlcThread(FAULT_PROGRAM, stepped=True) as plc, RawModbusClient("127.0.0.1", plc.port) as c:
        c.step(2)
        assert c.read_holding(1026, 1) == [100]
        c.write_register(1024, 0)
        with pytest.raises(ModbusException) as info:
            c.step(1)
        assert info.value.code == 4
        status = c.status()
        assert status.faulted and status.fault_code == control.FAULT_DIVISION_BY_ZERO, status
        c.write_register(1024, 2)
        c.reset_fault()
        c.step(1)
        assert c.read_holding(1026, 1) == [50]
        c.write_register(1025, 5)
        with pytest.raises(ModbusException):
            c.step(1)
        status = c.status()
        assert status.fault_code == control.FAULT_INDEX, status
        assert status.scan_count == 3


def test_pid_plant_conformance_over_modbus():
    folder = conformance_dir()
    if folder is None:
        pytest.skip("conformance corpus not found (set THERMOST_SHARED or keep ../shared/conformance)")
    expected = json.loads((folder / "pid_plant.expected.json").read_text())
    with (
        SoftPlcThread(folder / "pid_plant.st", stepped=True) as plc,
        RawModbusClient("127.0.0.1", plc.port) as c,
    ):
        c.step(expected["scans"])
        assert c.read_coils(0, 1) == [True]
        for result in expected["results"]:
            modbus = result["modbus"]
            assert modbus["table"] == "holding"
            got = c.read_holding(modbus["address"], modbus["count"])
            if result["compare"] == "exact":
                assert got == result["raw"], result["var"]


def test_no_file_runs_the_bundle():
    from plc.bundle import bundle_declarations

    if not any(d.kind == "CONFIGURATION" for d in bundle_declarations()):
        pytest.skip("the bundle has no CONFIGURATION yet (plc/app/)")
    plc = PlcProcess(["--stepped"])
    try:
        with RawModbusClient("127.0.0.1", plc.port) as client:
            client.step(3)
            status = client.status()
            assert status.scan_count == 3 and not status.faulted, status
            assert status.time_ns == 3 * status.interval_ns
    finally:
        code, err = plc.interrupt()
    assert code == 0, err
