"""The soft-PLC Modbus TCP server: OpenPLC map over the wire, unit ids, exceptions, stepping,
faults, malformed requests, real-time clock."""

from __future__ import annotations

import socket
import struct
import time

import pytest
from pymodbus.client import ModbusTcpClient

from plc.runtime import control
from plc.runtime.rawclient import ModbusException, RawModbusClient
from plc.runtime.server import SoftPlcThread
from tests.test_runtime_fake import INTERVAL_NS, FakeApplication

ILLEGAL_FUNCTION, ILLEGAL_ADDRESS, ILLEGAL_VALUE, DEVICE_FAILURE = 1, 2, 3, 4


def real_words(value: float) -> list[int]:
    return list(struct.unpack(">HH", struct.pack(">f", value)))


def words_real(words: list[int]) -> float:
    return struct.unpack(">f", struct.pack(">HH", *words))[0]


@pytest.fixture
def stepped():
    app = FakeApplication()
    with SoftPlcThread(app, stepped=True) as plc, RawModbusClient("127.0.0.1", plc.port) as client:
        yield app, plc, client


def exception_code(call, *args) -> int:
    with pytest.raises(ModbusException) as info:
        call(*args)
    return info.value.code


def test_pymodbus_client_any_unit_id_and_current_api(stepped):
    _, plc, _ = stepped
    client = ModbusTcpClient("127.0.0.1", port=plc.port)
    assert client.connect()
    try:
        values = client.convert_to_registers(1.5, client.DATATYPE.FLOAT32)
        assert not client.write_registers(2050, values, device_id=7).isError()
        for unit in (0, 1, 17, 255):
            reply = client.read_holding_registers(2050, count=2, device_id=unit)
            assert client.convert_from_registers(reply.registers, client.DATATYPE.FLOAT32) == 1.5
        reply = client.read_input_registers(1024, count=1, device_id=1)
        assert reply.isError() and reply.exception_code == ILLEGAL_ADDRESS
        reply = client.read_discrete_inputs(3, count=1, device_id=1)
        assert reply.bits[0] is True
    finally:
        client.close()


def test_exceptions_outside_openplc_ranges(stepped):
    _, _, c = stepped
    assert exception_code(c.read_input, 1024, 1) == ILLEGAL_ADDRESS
    assert exception_code(c.read_holding, 8192, 1) == ILLEGAL_ADDRESS
    assert exception_code(c.read_holding, 8190, 4) == ILLEGAL_ADDRESS
    assert exception_code(c.read_holding, 59999, 1) == ILLEGAL_ADDRESS
    last_control = control.CONTROL_BASE + control.CONTROL_SIZE - 1
    assert exception_code(c.read_holding, last_control, 2) == ILLEGAL_ADDRESS
    assert exception_code(c.read_coils, 8192, 1) == ILLEGAL_ADDRESS
    assert exception_code(c.write_register, control.STATUS, 0) == ILLEGAL_ADDRESS  # read only
    assert c.read_holding(8191, 1) == [0]


def test_step_runs_scans_before_acknowledging(stepped):
    app, _, c = stepped
    c.write_registers(2050, real_words(1.25))
    c.write_register(1024, 41)
    assert c.status().scan_count == 0
    c.step(3)
    status = c.status()
    assert (status.scan_count, status.time_ns, status.time_ms) == (3, 3 * INTERVAL_NS, 30)
    assert status.interval_ns == INTERVAL_NS and status.stepped and not status.faulted
    assert words_real(c.read_holding(2052, 2)) == 2.5
    assert c.read_holding(1025, 1) == [42]
    assert c.read_holding(2048, 2) == [0, 3]
    assert c.read_holding(control.STEP, 1) == [3]  # FC6 echo reads back the last N
    assert exception_code(c.write_register, control.STEP, 0) == ILLEGAL_VALUE
    assert app.values["cnt"] == 3


def test_one_read_write_request_per_step_with_rw_steps(stepped):
    _, _, c = stepped
    c.set_rw_steps(1)
    for k, x in enumerate((0.5, 3.0, -7.25), start=1):
        out = c.read_write(2048, 6, 2050, real_words(x))
        assert out[0:2] == [0, k]  # cnt after exactly one scan per request
        assert words_real(out[4:6]) == 2 * x
    c.set_rw_steps(0)
    out = c.read_write(2048, 2, 2050, real_words(1.0))
    assert out == [0, 3]  # no scan any more
    out = c.read_write(2048, 2, control.STEP, [2])  # step + read in one request
    assert out == [0, 5]


def test_single_word_write_of_a_real_keeps_the_other_word(stepped):
    app, _, c = stepped
    c.write_registers(2050, real_words(2.5))
    c.write_register(2051, 0x0001)  # FC6 on the low word only
    assert c.read_holding(2050, 2) == [0x4020, 0x0001]
    assert app.values["in_real"] == words_real([0x4020, 0x0001])


def test_runtime_fault_stops_program_not_server(stepped, caplog):
    app, _, c = stepped
    c.step(2)
    c.write_register(1026, 0)  # divisor := 0
    assert exception_code(c.step, 5) == DEVICE_FAILURE
    status = c.status()
    assert status.faulted and status.fault_code == control.FAULT_DIVISION_BY_ZERO
    assert "division by zero" in status.fault_text
    assert status.scan_count == 2
    assert exception_code(c.step, 1) == DEVICE_FAILURE  # still stopped
    messages = [r.getMessage() for r in caplog.records]
    assert any("runtime fault" in m and "division by zero" in m for m in messages)
    assert c.read_holding(2048, 2) == [0, 3]  # served; the faulted scan got as far as cnt
    c.write_register(1026, 1)
    c.reset_fault()
    assert not c.status().faulted
    c.step(1)
    assert c.status().scan_count == 3
    c.write_register(1027, 9)  # index out of 0..3
    assert exception_code(c.step, 1) == DEVICE_FAILURE
    status = c.status()
    assert status.fault_code == control.FAULT_INDEX and "index 9" in status.fault_text
    assert app.fault is not None


def _raw_request(sock: socket.socket, pdu: bytes, tid: int = 1) -> bytes:
    sock.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, 1) + pdu)
    return _raw_reply(sock)


def _raw_reply(sock: socket.socket) -> bytes:
    header = sock.recv(7, socket.MSG_WAITALL)
    length = struct.unpack(">HHHB", header)[2]
    return header + sock.recv(length - 1, socket.MSG_WAITALL)


@pytest.mark.parametrize(
    ("pdu", "function", "code"),
    [
        (struct.pack(">BHH", 3, 2048, 0), 3, ILLEGAL_VALUE),  # zero quantity
        (struct.pack(">BHH", 3, 2048, 126), 3, ILLEGAL_VALUE),  # above 125
        (struct.pack(">BHH", 1, 0, 2001), 1, ILLEGAL_VALUE),
        (struct.pack(">BHHBH", 16, 1024, 2, 4, 1), 16, ILLEGAL_VALUE),  # byte count > data
        (bytes([0x41, 0, 0]), 0x41, ILLEGAL_FUNCTION),  # unknown function code
        (struct.pack(">BHH", 5, 0, 0x1234), 5, ILLEGAL_VALUE),  # coil value not 0/FF00
    ],
)
def test_malformed_requests_get_exceptions(stepped, pdu, function, code):
    _, plc, c = stepped
    with socket.create_connection(("127.0.0.1", plc.port), timeout=5) as sock:
        reply = _raw_request(sock, pdu)
        assert reply[7] == function | 0x80 and reply[8] == code
    assert c.read_holding(2048, 2) == [0, 0]  # server still serves


def test_garbage_and_truncated_frames_do_not_kill_the_server(stepped):
    _, plc, c = stepped
    with socket.create_connection(("127.0.0.1", plc.port), timeout=5) as sock:
        sock.sendall(b"GET / HTTP/1.0\r\n\r\n")  # protocol id != 0: dropped
        sock.sendall(struct.pack(">HHHB", 9, 0, 6, 1) + b"\x03\x08")  # truncated, then closed
    with socket.create_connection(("127.0.0.1", plc.port), timeout=5) as sock:
        sock.sendall(struct.pack(">HHHB", 9, 0, 1, 1))  # only a unit id, no function code
        assert _raw_request(sock, struct.pack(">BHH", 3, 2048, 2), tid=10)[9:] == b"\0\0\0\0"
    assert c.status().scan_count == 0


def test_pipelined_requests_are_answered_in_order(stepped):
    _, plc, _ = stepped
    with socket.create_connection(("127.0.0.1", plc.port), timeout=5) as sock:
        requests = ((1, struct.pack(">BHH", 6, control.STEP, 2)), (2, struct.pack(">BHH", 3, 2048, 2)))
        frames = b"".join(struct.pack(">HHHB", tid, 0, len(pdu) + 1, 1) + pdu for tid, pdu in requests)
        sock.sendall(frames)
        first, second = _raw_reply(sock), _raw_reply(sock)
    assert first[:2] == b"\0\x01" and second[:2] == b"\0\x02"
    assert second[9:] == b"\0\0\0\x02"


def wait_for(client: RawModbusClient, condition, timeout_s: float = 5.0) -> control.PlcStatus:
    """Poll the control block until `condition(status)` holds (real-time tests on shared CPUs)."""
    deadline = time.monotonic() + timeout_s
    while True:
        status = client.status()
        if condition(status) or time.monotonic() > deadline:
            assert condition(status), status
            return status
        time.sleep(0.01)


def test_real_time_mode_scans_on_the_task_interval():
    app = FakeApplication()
    with SoftPlcThread(app, stepped=False) as plc, RawModbusClient("127.0.0.1", plc.port) as c:
        start = time.monotonic()
        time.sleep(0.3)
        status = c.status()
        elapsed = time.monotonic() - start
        assert not status.stepped
        expected = elapsed / (INTERVAL_NS / 1e9)
        assert expected * 0.3 <= status.scan_count <= expected + 3  # lower bound loose: shared CPUs
        assert status.time_ns == status.scan_count * INTERVAL_NS
        assert exception_code(c.step, 1) == ILLEGAL_ADDRESS  # no stepping in real time
        c.write_register(1026, 0)  # fault in real time: status readable, server alive
        status = wait_for(c, lambda s: s.faulted)
        assert status.fault_code == control.FAULT_DIVISION_BY_ZERO
        frozen = status.scan_count
        time.sleep(0.05)
        assert c.status().scan_count == frozen
        c.write_register(1026, 1)
        c.reset_fault()
        wait_for(c, lambda s: s.scan_count > frozen)


class SlowApplication(FakeApplication):
    """Scans take 2.5 intervals: the real-time clock must count overruns and not burst."""

    def scan(self) -> None:
        time.sleep(2.5 * self.interval_ns / 1e9)
        super().scan()


def test_real_time_overruns_are_counted():
    with SoftPlcThread(SlowApplication(), stepped=False) as plc, RawModbusClient("127.0.0.1", plc.port) as c:
        time.sleep(0.25)
        status = c.status()
    assert status.overruns >= 1
    assert status.scan_count <= 0.25 / (2.5 * INTERVAL_NS / 1e9) + 2  # no catch-up burst


def test_random_requests_always_get_a_reply_and_never_close_the_connection(stepped):
    """Seeded fuzz: known and unknown function codes with random payloads, any unit id."""
    import random

    _, plc, c = stepped
    rng = random.Random(61131)
    codes = [1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 15, 16, 17, 20, 21, 22, 23, 24, 43, 0x83, 0]
    with socket.create_connection(("127.0.0.1", plc.port), timeout=5) as sock:
        for tid in range(1, 1500):
            function = rng.choice([*codes, rng.randrange(256)])
            pdu = bytes([function]) + bytes(rng.randrange(256) for _ in range(rng.randrange(12)))
            sock.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, rng.randrange(256)) + pdu)
            reply = _raw_reply(sock)
            assert struct.unpack(">H", reply[:2])[0] == tid, pdu.hex()
    assert c.status().version == control.CONTROL_BLOCK_VERSION


def test_async_context_manager_with_pymodbus_async_client_in_the_same_loop():
    import asyncio

    from pymodbus.client import AsyncModbusTcpClient

    from plc.runtime.server import SoftPlc

    async def scenario() -> list[int]:
        async with SoftPlc(FakeApplication(), port=0, stepped=True) as plc:
            client = AsyncModbusTcpClient("127.0.0.1", port=plc.port)
            await client.connect()
            try:
                await client.write_register(control.STEP, 4, device_id=1)
                reply = await client.readwrite_registers(
                    read_address=2048, read_count=2, write_address=control.STEP, values=[1], device_id=1
                )
                return reply.registers
            finally:
                client.close()

    assert asyncio.run(scenario()) == [0, 5]
