"""Pipelined Modbus requests: a burst far larger than one frame in one TCP segment is answered in order
(pymodbus alone drops any receive buffer over 264 bytes)."""

from __future__ import annotations

import socket
import struct

from plc.runtime.server import SoftPlcThread
from tests.test_runtime_fake import FakeApplication

HOLDING_BASE = 1024  # %MW0 (OpenPLC map)
FC16_WORDS = 123  # the largest FC16 (Modbus: 123 registers)
FC3_COUNT = 30


def mbap(tid: int, pdu: bytes) -> bytes:
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, 1) + pdu


def read_reply(sock: socket.socket) -> tuple[int, bytes]:
    head = b""
    while len(head) < 7:
        head += sock.recv(7 - len(head))
    tid, _, length, _ = struct.unpack(">HHHB", head)
    body = b""
    while len(body) < length - 1:
        body += sock.recv(length - 1 - len(body))
    return tid, body


def test_thirty_reads_and_two_full_writes_in_one_segment_are_all_answered():
    app = FakeApplication()
    with SoftPlcThread(app, stepped=True) as plc:
        words_a = list(range(1, FC16_WORDS + 1))
        words_b = [0xA000 + i for i in range(FC16_WORDS)]
        frames = [mbap(1, struct.pack(">BHHB", 16, HOLDING_BASE, FC16_WORDS, 2 * FC16_WORDS)
                       + struct.pack(f">{FC16_WORDS}H", *words_a)),
                  mbap(2, struct.pack(">BHHB", 16, HOLDING_BASE + FC16_WORDS, FC16_WORDS, 2 * FC16_WORDS)
                       + struct.pack(f">{FC16_WORDS}H", *words_b))]
        frames += [mbap(10 + i, struct.pack(">BHH", 3, HOLDING_BASE + 4 * i, 4)) for i in range(FC3_COUNT)]
        burst = b"".join(frames)
        assert len(burst) > 264 * 2
        with socket.create_connection(("127.0.0.1", plc.port), timeout=5.0) as sock:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            sock.sendall(burst)
            replies = [read_reply(sock) for _ in frames]
    expected = [1, 2] + [10 + i for i in range(FC3_COUNT)]
    assert [tid for tid, _ in replies] == expected, "every request, in order"
    assert replies[0][1] == struct.pack(">BHH", 16, HOLDING_BASE, FC16_WORDS)
    assert replies[1][1] == struct.pack(">BHH", 16, HOLDING_BASE + FC16_WORDS, FC16_WORDS)
    for i, (_, body) in enumerate(replies[2:]):
        assert body[:2] == bytes([3, 8])
        got = list(struct.unpack(">4H", body[2:]))
        assert got == words_a[4 * i: 4 * i + 4], f"read {i} sees the write before it"
