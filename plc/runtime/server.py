"""The soft-PLC Modbus TCP server (pymodbus) with a real-time or stepped clock.

`SoftPlc` is an async context manager; `SoftPlcThread` runs the same in a background
thread for synchronous callers. Requests are answered as soon as they are decoded, in
order (pipelined requests included), without an extra event-loop round per request.
"""

from __future__ import annotations

import asyncio
import logging
import struct
import threading
from pathlib import Path

from pymodbus.constants import ExcCodes
from pymodbus.pdu import ExceptionResponse, ModbusPDU
from pymodbus.server import ModbusTcpServer
from pymodbus.server.requesthandler import ServerRequestHandler
from pymodbus.transaction import TransactionManager

from plc.runtime.datastore import PlcDatastore
from plc.runtime.engine import ApplicationLike, PlcEngine
from plc.runtime.image import ModbusImage

log = logging.getLogger("thermost.plc")

NS_PER_S = 1e9
MBAP_SIZE = 7  # transaction id, protocol id, length, unit id
MBAP_PROTOCOL_SLICE = slice(2, 4)
MBAP = struct.Struct(">HHHB")
WRITE_SINGLE_COIL = 5
FC5_FRAME_SIZE = MBAP_SIZE + 5  # function, address, value
FC5_VALUE_SLICE = slice(MBAP_SIZE + 3, MBAP_SIZE + 5)
COIL_VALUES = (0x0000, 0xFF00)
MBAP_LENGTH_SLICE = slice(4, 6)
MBAP_LENGTH_OFFSET = 6  # the MBAP length counts the bytes after itself
EXCEPTION_FLAG = 0x80
LATE_SCANS_MADE_UP = 1  # real-time scheduler: a scan up to this many intervals late runs, later ones skip
PIPELINE_BUFFER_BYTES = 1 << 20  # unprocessed request bytes kept per connection (a TCP window is 64 KiB+)


def load_program(program: ApplicationLike | Path | str, filename: str = "<source>") -> ApplicationLike:
    """An `Application` from an application object, a `.st` path, or ST source text."""
    if hasattr(program, "scan"):
        return program  # type: ignore[return-value]
    from plc.st.compiler import load_application

    if isinstance(program, Path):
        return load_application([(str(program), program.read_text(encoding="utf-8"))])
    return load_application([(filename, str(program))])


def _refused_single_coil_frame(frame: bytes) -> int | None:
    """Length of a complete FC5 frame whose value is neither 0x0000 nor 0xFF00 (Modbus: exception 3)."""
    if len(frame) < FC5_FRAME_SIZE or frame[MBAP_SIZE] != WRITE_SINGLE_COIL:
        return None
    frame_size = MBAP_LENGTH_OFFSET + int.from_bytes(frame[MBAP_LENGTH_SLICE], "big")
    if len(frame) < frame_size:
        return None
    value = int.from_bytes(frame[FC5_VALUE_SLICE], "big")
    return frame_size if value not in COIL_VALUES else None


class _PlcRequestHandler(ServerRequestHandler):
    """Per-connection handler: decodes every frame in the buffer and answers it at once.

    pymodbus drops a receive buffer longer than its framer's MAX_SIZE (264 bytes: one frame), so 23 FC3
    requests or two 123-register FC16 arriving in one TCP segment were lost without a reply. The handler
    keeps up to PIPELINE_BUFFER_BYTES of unprocessed data instead: any pipelined burst that fits a TCP
    receive window is answered, frame by frame, in order.
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.max_buffer_size = PIPELINE_BUFFER_BYTES

    def callback_data(self, data: bytes, addr: tuple | None = None) -> int:
        consumed = 0
        while consumed < len(data):
            rest = data[consumed:]
            if len(rest) >= MBAP_SIZE and rest[MBAP_PROTOCOL_SLICE] != b"\0\0":
                log.warning("dropping %d bytes: not Modbus TCP (protocol id is not 0)", len(rest))
                return len(data)
            if (refused := _refused_single_coil_frame(rest)) is not None:
                self._send_exception(rest, ExcCodes.ILLEGAL_VALUE, addr)
                consumed += refused
                continue
            try:
                used = TransactionManager.callback_data(self, rest, addr)
            except Exception as exc:  # noqa: BLE001 - undecodable request: exception reply, never a crash
                self._answer_undecodable(exc, rest, addr)
                return len(data)
            if self.last_pdu is not None:
                self._answer(self.last_pdu, addr)
            if used == 0:
                break
            consumed += used
        return consumed

    def _answer_undecodable(self, exc: Exception, frame: bytes, addr: tuple | None) -> None:
        """A frame pymodbus cannot decode: bad quantity/length for a known code, or an unknown code."""
        function_code = frame[MBAP_SIZE] & 0x7F if len(frame) > MBAP_SIZE else 0
        known = function_code in self.server.decoder.list_function_codes()
        self._send_exception(frame, ExcCodes.ILLEGAL_VALUE if known else ExcCodes.ILLEGAL_FUNCTION, addr)

    def _send_exception(self, frame: bytes, code: ExcCodes, addr: tuple | None) -> None:
        """Exception response to the (raw) request at the start of `frame`."""
        tid, _, _, unit = MBAP.unpack_from(frame)
        function_code = frame[MBAP_SIZE] & 0x7F if len(frame) > MBAP_SIZE else 0
        response = ExceptionResponse(function_code, exception_code=code, device_id=unit, transaction=tid)
        self.server_send(response, addr)

    def _answer(self, pdu: ModbusPDU, addr: tuple | None) -> None:
        response = self._response_to(pdu)
        response.transaction_id = pdu.transaction_id
        response.dev_id = pdu.dev_id
        try:
            self.server_send(response, addr)
        except Exception as exc:  # noqa: BLE001 - e.g. pymodbus cannot encode its reply to a garbage request
            code = pdu.function_code
            log.warning("reply to function %d cannot be encoded (%s); exception 4 instead", code, exc)
            failure = ExceptionResponse(code, ExcCodes.DEVICE_FAILURE, pdu.dev_id, pdu.transaction_id)
            self.server_send(failure, addr)

    def _response_to(self, pdu: ModbusPDU) -> ModbusPDU:
        if pdu.function_code & EXCEPTION_FLAG:  # an exception response sent as a request
            return ExceptionResponse(pdu.function_code, ExcCodes.ILLEGAL_FUNCTION)
        coroutine = pdu.datastore_update(self.server.context, pdu.dev_id)
        try:
            coroutine.send(None)
        except StopIteration as done:
            return done.value
        except Exception as exc:  # noqa: BLE001 - a request must never take the server down
            log.warning("request function %d failed: %s: %s", pdu.function_code, type(exc).__name__, exc)
            log.debug("request function %d failed", pdu.function_code, exc_info=True)
            return ExceptionResponse(pdu.function_code, ExcCodes.DEVICE_FAILURE)
        # the datastore never awaits; a PDU handler that does is not supported
        coroutine.close()
        log.error("request function %d needs an asynchronous handler; refused", pdu.function_code)
        return ExceptionResponse(pdu.function_code, ExcCodes.ILLEGAL_FUNCTION)


class _PlcTcpServer(ModbusTcpServer):
    def callback_new_connection(self) -> ServerRequestHandler:
        return _PlcRequestHandler(self, self.trace_packet, self.trace_pdu, self.trace_connect)


class RealTimeClock:
    """Runs one scan every TASK interval of wall time, on absolute deadlines (no drift)."""

    def __init__(self, engine: PlcEngine, loop: asyncio.AbstractEventLoop):
        self.engine = engine
        self.loop = loop
        self._deadline = 0.0
        self._handle: asyncio.TimerHandle | None = None

    def start(self) -> None:
        self._deadline = self.loop.time()
        self._handle = self.loop.call_at(self._deadline, self._tick)

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def _tick(self) -> None:
        with self.engine.lock:
            self.engine.scan_once()
        interval = self.engine.interval_ns / NS_PER_S
        self._deadline += interval
        now = self.loop.time()
        if now - self._deadline > LATE_SCANS_MADE_UP * interval:
            self.engine.overruns += 1
            self._deadline = now
        self._handle = self.loop.call_at(self._deadline, self._tick)


class SoftPlc:
    """Soft-PLC: Modbus TCP server with OpenPLC's map over a PLC program.

    `async with SoftPlc(program, port=0, stepped=True) as plc:` then `plc.port`.
    """

    def __init__(self, program: ApplicationLike | Path | str, host: str = "127.0.0.1", port: int = 0,
                 stepped: bool = False):
        app = load_program(program)
        if int(app.interval_ns) <= 0:
            raise ValueError(f"the program's task interval must be positive, not {app.interval_ns} ns")
        self.engine = PlcEngine(app, stepped)
        self.image = ModbusImage(app.located)
        self.host = host
        self.requested_port = port
        self.port: int | None = None
        self.stepped = stepped
        self._server: _PlcTcpServer | None = None
        self._clock: RealTimeClock | None = None
        self._stopped: asyncio.Event | None = None

    @property
    def app(self) -> ApplicationLike:
        return self.engine.app

    async def start(self) -> None:
        self._stopped = asyncio.Event()
        datastore = PlcDatastore(self.image, self.engine)
        server = _PlcTcpServer(datastore, address=(self.host, self.requested_port))
        try:
            await server.serve_forever(background=True)
        except RuntimeError as exc:
            raise OSError(f"cannot listen on {self.host}:{self.requested_port}") from exc
        self._server = server
        self.port = server.transport.sockets[0].getsockname()[1]  # type: ignore[union-attr]
        if not self.stepped:
            self._clock = RealTimeClock(self.engine, asyncio.get_running_loop())
            self._clock.start()

    def stop(self) -> None:
        """Ask `serve_forever` to return (safe to call from the loop's thread only)."""
        if self._stopped is not None:
            self._stopped.set()

    async def close(self) -> None:
        if self._clock is not None:
            self._clock.stop()
            self._clock = None
        if self._server is not None:
            await self._server.shutdown()
            self._server = None

    async def serve_forever(self) -> None:
        assert self._stopped is not None, "start() first"
        await self._stopped.wait()

    async def __aenter__(self) -> SoftPlc:
        await self.start()
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        await self.close()


class SoftPlcThread:
    """`SoftPlc` in a background thread with its own event loop: `with SoftPlcThread(...) as plc:`."""

    def __init__(self, program: ApplicationLike | Path | str, host: str = "127.0.0.1", port: int = 0,
                 stepped: bool = False):
        self.plc = SoftPlc(program, host, port, stepped)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def port(self) -> int:
        assert self.plc.port is not None
        return self.plc.port

    @property
    def engine(self) -> PlcEngine:
        return self.plc.engine

    def _run(self) -> None:
        loop = self._loop
        assert loop is not None
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(self._main())
        except BaseException as exc:  # noqa: BLE001 - reported to the starting thread
            self._error = exc
        finally:
            self._ready.set()
            loop.close()

    async def _main(self) -> None:
        async with self.plc:
            self._ready.set()
            await self.plc.serve_forever()

    def __enter__(self) -> SoftPlcThread:
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name="soft-plc", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            raise self._error
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._loop is not None and self._thread is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self.plc.stop)
            self._thread.join()
