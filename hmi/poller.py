"""The panel's only link to the PLC: one Modbus TCP connection, polled in block reads.

Every cycle (default 10 Hz) the live registers of all zones are read in as few requests as the register
map allows (`PlcClient.read_tags` plans contiguous spans); about once a second the rest (parameters,
identified plant, diagnostics). Each sample is timestamped when its read completes and gets a sequence
number, so pages send the browser only the samples it has not seen. Writes go through the same
connection (an asyncio lock keeps requests sequential), 32-bit values in one FC16 request, and every
write is read back and audited. The poll loop never waits for a page.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import statistics
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from modbus_bridge.alarm_texts import alarm_texts, describe_bits, error_texts
from modbus_bridge.client import PlcClient, PlcError

from .model import PanelModel
from .store import Store

SLOW_EVERY_S = 1.0
RECONNECT_S = 0.5
STALE_AFTER_CYCLES = 3
HISTORY_S = 600.0
STORE_EVERY_S = 1.0
READBACK_DELAY_S = 0.35  # let the PLC scan (and validate) a write before it is read back
PARAM_ERROR_BIT = 16
PARAM_ERROR_IDS = (1, 2, 3)  # FB_CtrlParamCheck's error ids: task cycle, control cycle, any other parameter
LATENCY_WINDOW = 600


@dataclass
class Sample:
    seq: int
    t: float  # wall clock (s since the epoch) when the read completed
    values: dict


@dataclass
class WriteResult:
    ok: bool
    message: str
    shown: dict = field(default_factory=dict)  # what the PLC shows after the write


@dataclass
class Diagnostics:
    connected: bool = False
    error: str = "not connected yet"
    last_ok: float = 0.0
    cycles: int = 0
    failures: int = 0
    reconnects: int = 0
    requests_per_cycle: int = 0
    latency_ms: deque = field(default_factory=lambda: deque(maxlen=LATENCY_WINDOW))
    scan_rate_hz: float | None = None
    scan_count: int | None = None
    fault_text: str = ""


class Poller:
    def __init__(self, model: PanelModel, host: str, port: int, *, rate_hz: float = 10.0,
                 store: Store | None = None) -> None:
        self.model, self.host, self.port, self.rate_hz, self.store = model, host, port, rate_hz, store
        self.client = PlcClient(host, port, model.regmap, timeout_s=1.0, retries=0, name="PLC")
        self.lock = asyncio.Lock()
        self.fast = model.fast_tags()
        self.slow = model.slow_tags()
        self.values: dict = {}
        self.samples: deque[Sample] = deque(maxlen=int(HISTORY_S * rate_hz))
        self.seq = 0
        self.diag = Diagnostics()
        self.alarm_text = alarm_texts()
        self.error_text = error_texts()
        self._alarm_words: dict[int, int] = {}
        self._in_flight: set[str] = set()
        self._last_store = 0.0
        self._scan_ref: tuple[float, int] | None = None
        self._task: asyncio.Task | None = None
        self._slow_due = False  # a zone changed state: read the parameters / identified plant now
        self.listeners: set[Callable[[], None]] = set()
        self._stop = asyncio.Event()

    # --- life cycle ---------------------------------------------------------------------------------
    def start(self) -> None:
        self._task = asyncio.get_running_loop().create_task(self.run())

    async def stop(self) -> None:
        self._stop.set()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        self.client.close()

    @property
    def stale(self) -> bool:
        return bool(self.stale_reason())

    def stale_reason(self) -> str:
        """Why the values shown cannot be trusted for a write ("" when they are fresh): no connection, or
        no answer for longer than a few poll cycles (the PLC, the network or this panel stalled)."""
        if not self.diag.connected:
            return "the PLC is not reachable"
        age = time.time() - self.diag.last_ok
        if age > STALE_AFTER_CYCLES / self.rate_hz + 0.5:
            return f"no fresh values from the PLC for {age:.1f} s"
        return ""

    async def run(self) -> None:
        period = 1.0 / self.rate_hz
        next_slow = 0.0
        next_t = time.perf_counter()
        while not self._stop.is_set():
            try:
                if time.perf_counter() >= next_slow or self._slow_due:
                    self._slow_due = False
                    await self._read_slow()
                    next_slow = time.perf_counter() + SLOW_EVERY_S
                await self._read_fast()
            except PlcError as exc:
                self._lost(str(exc))
                await asyncio.sleep(RECONNECT_S)
                next_t = time.perf_counter()
                continue
            next_t += period
            delay = next_t - time.perf_counter()
            if delay < 0:
                next_t = time.perf_counter()
                delay = 0
            await asyncio.sleep(delay)

    def _lost(self, why: str) -> None:
        if self.diag.connected:
            self.diag.reconnects += 1
        self.diag.connected = False
        self.diag.failures += 1
        self.diag.error = why
        self.client.close()

    async def _read_fast(self) -> None:
        t0 = time.perf_counter()
        async with self.lock:
            values = await self.client.read_tags(self.fast)
        now = time.time()
        self.diag.latency_ms.append((time.perf_counter() - t0) * 1e3)
        self.diag.requests_per_cycle = len(self.client._plan(self.fast))
        self.diag.cycles += 1
        self.diag.connected, self.diag.error, self.diag.last_ok = True, "", now
        states = [z["state"] for z in self.model.zones]
        if any(values.get(n) != self.values.get(n) for n in states):
            self._slow_due = True
        self.values.update(values)
        self.seq += 1
        self.samples.append(Sample(self.seq, now, values))
        for listener in list(self.listeners):  # pages that stream samples (the trend)
            try:
                listener()
            except Exception:  # noqa: BLE001 - a page that went away must not stop the poll loop
                self.listeners.discard(listener)
        self._track_alarms(values)
        self._store(now, values)

    async def _read_slow(self) -> None:
        async with self.lock:
            self.values.update(await self.client.read_tags(self.slow))
            try:
                count = await self.client.scan_count()
            except PlcError as exc:
                if "refused" not in str(exc):
                    raise
                count = None  # a real OpenPLC has no soft-PLC control block
        now = time.time()
        self.diag.scan_count = count
        if count is not None:
            if self._scan_ref is not None and now > self._scan_ref[0] and count >= self._scan_ref[1]:
                self.diag.scan_rate_hz = (count - self._scan_ref[1]) / (now - self._scan_ref[0])
            self._scan_ref = (now, count)

    # --- alarms and history -------------------------------------------------------------------------
    def alarm_word(self, zone: int) -> int:
        z = self.model.zones[zone - 1]
        return int(self.values.get(z["alarm"], 0)) if z.has("alarm") else 0

    def active_alarms(self) -> list[tuple[int, int, str]]:
        return [(z.number, b, text) for z in self.model.zones
                for b, text in describe_bits(self.alarm_word(z.number), self.alarm_text)]

    def _track_alarms(self, values: dict) -> None:
        for z in self.model.zones:
            if not z.has("alarm"):
                continue
            word = int(values[z["alarm"]])
            old = self._alarm_words.get(z.number)
            self._alarm_words[z.number] = word
            if old is None or old == word or self.store is None:
                if old is None and word and self.store is not None:
                    for b, text in describe_bits(word, self.alarm_text):
                        self.store.add_alarm_event(z.number, b, "active at start", text)
                continue
            for b, text in describe_bits(word & ~old, self.alarm_text):
                self.store.add_alarm_event(z.number, b, "raised", text)
            for b, text in describe_bits(old & ~word, self.alarm_text):
                self.store.add_alarm_event(z.number, b, "cleared", text)

    def _store(self, now: float, values: dict) -> None:
        if self.store is None or now - self._last_store < STORE_EVERY_S:
            return
        self._last_store = now
        rows = []
        for z in self.model.zones:
            def v(role: str, z=z):
                return values.get(z.tags.get(role, ""), self.values.get(z.tags.get(role, "")))
            rows.append((now, z.number, v("pv"), v("setpoint"), v("y"), v("state"), v("alarm"),
                         v("kp_eff") if z.has("kp_eff") else v("kp"),
                         v("tn_eff") if z.has("tn_eff") else v("tn"),
                         v("tv_eff") if z.has("tv_eff") else v("tv")))
        self.store.add_samples(rows)
        self.store.prune(now)

    # --- writes -------------------------------------------------------------------------------------
    async def write(self, values: dict, level: str, *, verify: bool = True) -> WriteResult:
        """Write tags (one FC16 per contiguous block), read them back, audit old -> new and the outcome."""
        names = list(values)
        busy = [n for n in names if n in self._in_flight]
        if busy:
            return WriteResult(False, f"{', '.join(busy)}: a write is still in progress")
        self._in_flight.update(names)
        try:
            return await self._write(values, level, verify)
        finally:
            self._in_flight.difference_update(names)

    async def _write(self, values: dict, level: str, verify: bool) -> WriteResult:
        names = list(values)
        old = {n: self.values.get(n) for n in names}
        words_before = {z.number: int(self.values.get(z.tags.get("alarm", ""), 0) or 0)
                        for z in self.model.zones}
        zones = {self.model.meta[n].zone for n in values if n in self.model.meta}
        try:
            async with self.lock:
                await self.client.write_tags(values)
        except (PlcError, ValueError, TypeError) as exc:
            self._audit(level, values, old, "failed", str(exc))
            if isinstance(exc, PlcError) and "refused" not in str(exc):
                self._lost(str(exc))
            return WriteResult(False, f"not written: {exc}")
        if not verify:
            self._audit(level, values, old, "written", "")
            return WriteResult(True, "written")
        await asyncio.sleep(READBACK_DELAY_S)
        try:
            async with self.lock:
                shown = await self.client.read_tags(names + self._status_tags(zones))
        except PlcError as exc:
            self._audit(level, values, old, "unconfirmed", str(exc))
            return WriteResult(False, f"written, but not read back: {exc}")
        self.values.update(shown)
        refused = [n for n in names if self.model.meta[n].owner != "command"
                   and not _same(values[n], shown[n], self.model.regmap[n].iec_type)]
        problems = []
        if refused:
            kept = [f"{n} = {shown[n]:.6g}" if isinstance(shown[n], float) else f"{n} = {shown[n]}"
                    for n in refused]
            problems.append("the PLC keeps " + ", ".join(kept))
        for z in zones:
            if z is None:
                continue
            zm = self.model.zones[z - 1]
            word = int(shown.get(zm.tags.get("alarm", ""), 0) or 0)
            err = int(shown.get(zm.tags.get("error", ""), 0) or 0)
            was_set = words_before.get(z, 0) >> PARAM_ERROR_BIT & 1
            # a latched bit from an earlier refusal stays until acknowledged: then the error id decides (an
            # alarm reaction's id is no refusal; a value the PLC kept shows in the read-back above)
            if word >> PARAM_ERROR_BIT & 1 and (not was_set or err in PARAM_ERROR_IDS):
                why = self.error_text.get(err, f"error id {err}") if err else f"alarm bit {PARAM_ERROR_BIT}"
                problems.append(f"zone {z}: parameter error ({why})")
        if problems:
            message = "refused by the PLC: " + "; ".join(problems)
            self._audit(level, values, old, "refused", message)
            return WriteResult(False, message, shown)
        self._audit(level, values, old, "accepted", "")
        return WriteResult(True, "accepted by the PLC", shown)

    def _status_tags(self, zones: set) -> list[str]:
        out = []
        for z in zones:
            if z is not None:
                zm = self.model.zones[z - 1]
                out += [zm[r] for r in ("alarm", "error") if zm.has(r)]
        return out

    def _audit(self, level: str, values: dict, old: dict, result: str, message: str) -> None:
        if self.store is None:
            return
        for n, v in values.items():
            self.store.add_audit(level, n, old.get(n), v, result, message)

    # --- figures for diagnostics and bench ----------------------------------------------------------
    def latency_stats(self) -> tuple[float, float]:
        lat = sorted(self.diag.latency_ms)
        if not lat:
            return math.nan, math.nan
        return statistics.median(lat), lat[min(len(lat) - 1, int(0.95 * len(lat)))]


def _same(wanted: object, shown: object, iec_type: str) -> bool:
    if isinstance(wanted, bool) or isinstance(shown, bool):
        return bool(wanted) == bool(shown)
    if iec_type in ("REAL", "LREAL"):
        w, s = float(wanted), float(shown)
        if math.isnan(w) or math.isnan(s):
            return math.isnan(w) and math.isnan(s)
        return abs(w - s) <= 1e-6 * max(1.0, abs(w))
    return int(wanted) == int(shown)
