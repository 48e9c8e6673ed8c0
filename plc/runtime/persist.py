"""Persistent storage as OpenPLC v3 does it (`start_pstorage(N)`, reference/openplc.md).

Kept: every located `%MW`, `%MD` and `%ML` variable (OpenPLC keeps the 1024 of each). Not kept: `%QW`,
`%IW`, `%QX`/`%IX` (coils and discrete inputs). Saved every `period_s` when a kept value changed (and
once more when the soft-PLC stops cleanly); restored before the first scan, except values saved as
zero, which keep their initial value (OpenPLC restores only non-zero registers). The application then
decides on its first scan what to do with them (plc/app: `nStoreSignature`).

File: JSON, `{"format": FORMAT, "registers": {"%MD6": [word, word], ...}}`, the raw Modbus words (high
word first) of each variable, so a REAL comes back bit for bit; written to a temporary file, then
renamed, so a crash never leaves half a store.
"""

from __future__ import annotations

import json
import logging
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

from plc.runtime.image import ModbusImage, Slot

log = logging.getLogger("thermost.plc")

FORMAT = "thermost persistent storage 1"
KEPT_SIZES = ("W", "D", "L")
OPENPLC_MAX_INDEX = 1024  # %MW0..%MW1023, %MD0..%MD1023, %ML0..%ML1023
DEFAULT_PERIOD_S = 10.0  # the web UI's default polling period of start_pstorage


class PersistError(ValueError):
    """The store file cannot be read or written (one clear line)."""


def kept_slots(image: ModbusImage) -> list[Slot]:
    """The located variables OpenPLC's persistent storage keeps."""
    return sorted(
        (
            s
            for s in image.slots()
            if s.var.area.upper() == "M"
            and s.var.size.upper() in KEPT_SIZES
            and 0 <= s.var.index < OPENPLC_MAX_INDEX
        ),
        key=lambda s: (s.var.size.upper(), s.var.index),
    )


@dataclass
class PersistentStore:
    path: Path
    image: ModbusImage
    lock: threading.Lock
    period_s: float = DEFAULT_PERIOD_S
    last_saved: dict[str, list[int]] = field(default_factory=dict)
    saves: int = 0

    def snapshot(self) -> dict[str, list[int]]:
        with self.lock:
            return {s.var.location.upper(): s.words() for s in kept_slots(self.image)}

    def restore(self) -> int:
        """Before the first scan: non-zero saved values back into their variables; returns how many."""
        if not self.path.exists():
            log.info("persistent storage %s: blank store (no file yet)", self.path)
            return 0
        try:
            doc = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise PersistError(f"{self.path}: not a persistent-storage file ({exc})") from None
        valid = isinstance(doc, dict) and doc.get("format") == FORMAT
        valid = valid and isinstance(doc.get("registers"), dict)
        if not valid:
            raise PersistError(f"{self.path}: not a persistent-storage file (format {FORMAT!r} expected)")
        saved: dict = doc["registers"]
        restored = 0
        with self.lock:
            for slot in kept_slots(self.image):
                words = saved.get(slot.var.location.upper())
                if not isinstance(words, list) or len(words) != slot.place.n_words:
                    continue
                if not all(isinstance(w, int) and 0 <= w <= 0xFFFF for w in words) or not any(words):
                    continue  # saved as zero: the variable keeps its initial value
                slot.store_words(list(words))
                restored += 1
        self.last_saved = {k: v for k, v in saved.items() if isinstance(v, list)}
        log.info("persistent storage %s: %d register value(s) restored", self.path, restored)
        return restored

    def save_if_changed(self) -> bool:
        current = self.snapshot()
        if current == self.last_saved:
            return False
        tmp = self.path.with_name(self.path.name + ".tmp")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps({"format": FORMAT, "registers": current}) + "\n", encoding="utf-8")
            os.replace(tmp, self.path)
        except OSError as exc:
            log.error("persistent storage %s: cannot save: %s", self.path, exc.strerror or exc)
            return False
        self.last_saved = current
        self.saves += 1
        return True
