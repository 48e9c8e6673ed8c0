"""The Modbus client against a PLC that garbles replies (reference/openplc.md: the upstream runtime can
serve one socket from two threads and garble replies): a garbled or lost reply is retried on a fresh
connection, and a lost reply to a STEP never makes the PLC scan twice."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from modbus_bridge.client import PlcClient, PlcError
from modbus_bridge.regmap import load_register_map

server = pytest.importorskip("plc.runtime.server", reason="the soft-PLC runtime is needed")

PROGRAM = (Path(__file__).parent / "harness_fixtures" / "p_harness_test.st").read_text(encoding="utf-8")
REGMAP = load_register_map(sources=[("p_harness_test.st", PROGRAM)])


class GarblingProxy:
    """TCP proxy that corrupts (or drops) chosen replies, counted over all connections."""

    def __init__(self, target_port: int, bad_replies: set[int], mode: str) -> None:
        self.target_port, self.bad, self.mode = target_port, bad_replies, mode
        self.replies = 0
        self.server: asyncio.AbstractServer | None = None

    async def start(self) -> int:
        self.server = await asyncio.start_server(self._serve, "127.0.0.1", 0)
        return self.server.sockets[0].getsockname()[1]

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        up_reader, up_writer = await asyncio.open_connection("127.0.0.1", self.target_port)

        async def pump_requests() -> None:
            while data := await reader.read(4096):
                up_writer.write(data)
                await up_writer.drain()

        task = asyncio.create_task(pump_requests())
        try:
            while data := await up_reader.read(4096):
                self.replies += 1
                if self.replies in self.bad:
                    if self.mode == "drop":
                        continue
                    data = bytes([data[0] ^ 0xFF, data[1] ^ 0xFF]) + data[2:]  # wrong transaction id
                writer.write(data)
                await writer.drain()
        except ConnectionError:
            pass
        finally:
            task.cancel()
            writer.close()
            up_writer.close()

    def close(self) -> None:
        if self.server is not None:
            self.server.close()


@pytest.mark.parametrize("mode", ["garble", "drop"])
def test_bad_reply_to_a_read_is_retried(mode):
    async def go():
        async with server.SoftPlc(PROGRAM, port=0, stepped=True) as soft:
            proxy = GarblingProxy(soft.port, {2}, mode)
            port = await proxy.start()
            async with PlcClient("127.0.0.1", port, REGMAP, timeout_s=0.3, retries=2) as client:
                await client.write("fSetpointZone1", 42.5)  # reply 1
                value = await client.read("fSetpointZone1")  # reply 2 is bad, the retry succeeds
                retried = client.retried
            proxy.close()
            return value, retried

    value, retried = asyncio.run(go())
    assert value == 42.5 and retried >= 1


@pytest.mark.parametrize("mode", ["garble", "drop"])
def test_lost_step_reply_does_not_scan_twice(mode):
    async def go():
        async with server.SoftPlc(PROGRAM, port=0, stepped=True) as soft:
            proxy = GarblingProxy(soft.port, {3}, mode)  # 1: scan counter, 2: set RW_STEPS, 3: the step
            port = await proxy.start()
            async with PlcClient("127.0.0.1", port, REGMAP, timeout_s=0.3, retries=2) as client:
                values = await client.exchange({"fPvZone1": 20.0}, 5, ["fYZone1"])
                scans = await client.scan_count()
                retried = client.retried
            proxy.close()
            return values, scans, retried

    values, scans, retried = asyncio.run(go())
    assert retried >= 1
    assert scans == 5  # exactly the requested scans, although the reply to the step was lost
    assert "fYZone1" in values


def test_plc_that_never_answers_is_one_clear_error():
    async def go():
        async with server.SoftPlc(PROGRAM, port=0, stepped=True) as soft:
            proxy = GarblingProxy(soft.port, set(range(1, 100)), "drop")
            port = await proxy.start()
            client = PlcClient("127.0.0.1", port, REGMAP, timeout_s=0.2, retries=1)
            await client.connect()
            try:
                await client.read("fYZone1")
            finally:
                client.close()
                proxy.close()

    with pytest.raises(PlcError, match="stopped answering"):
        asyncio.run(go())
