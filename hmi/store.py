"""History and audit in SQLite (one file under the data folder, bounded retention).

Tables: `samples` (trend history, one row per zone and second), `alarm_events` (raised / cleared /
acknowledged), `audit` (every write made from the panel: time, level, tag, old -> new, result).
Writes are batched by the caller's poll loop; each call commits, so nothing is lost on a crash beyond
the current second.
"""

from __future__ import annotations

import json
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path

SCHEMA = """
CREATE TABLE IF NOT EXISTS samples (t REAL, zone INTEGER, pv REAL, w REAL, y REAL, state INTEGER,
                                    alarm INTEGER, kp REAL, tn REAL, tv REAL);
CREATE INDEX IF NOT EXISTS samples_t ON samples (t);
CREATE TABLE IF NOT EXISTS alarm_events (t REAL, zone INTEGER, bit INTEGER, event TEXT, text TEXT,
                                         level TEXT);
CREATE INDEX IF NOT EXISTS alarm_events_t ON alarm_events (t);
CREATE TABLE IF NOT EXISTS audit (t REAL, level TEXT, tag TEXT, old TEXT, new TEXT, result TEXT,
                                  message TEXT);
CREATE INDEX IF NOT EXISTS audit_t ON audit (t);
CREATE TABLE IF NOT EXISTS tune_sessions (zone INTEGER PRIMARY KEY, started REAL, before TEXT, decided TEXT);
"""
DB_NAME = "hmi.sqlite"


@dataclass
class Retention:
    samples_s: float = 7 * 86400.0
    events_s: float = 365 * 86400.0
    max_rows: int = 2_000_000  # per table, whatever the age


class Store:
    def __init__(self, data_dir: Path, retention: Retention | None = None) -> None:
        data_dir.mkdir(parents=True, exist_ok=True)
        self.path = data_dir / DB_NAME
        self.retention = retention or Retention()
        self.db = sqlite3.connect(self.path, check_same_thread=False)
        self.db.executescript(SCHEMA)
        self.db.execute("PRAGMA journal_mode=WAL")
        self._last_prune = 0.0

    def close(self) -> None:
        self.db.close()

    def add_samples(self, rows: list[tuple]) -> None:
        if rows:
            self.db.executemany("INSERT INTO samples VALUES (?,?,?,?,?,?,?,?,?,?)", rows)
            self.db.commit()

    def add_alarm_event(self, zone: int, bit: int, event: str, text: str, level: str = "") -> None:
        self.db.execute("INSERT INTO alarm_events VALUES (?,?,?,?,?,?)",
                        (time.time(), zone, bit, event, text, level))
        self.db.commit()

    def add_audit(self, level: str, tag: str, old: object, new: object, result: str, message: str) -> None:
        self.db.execute("INSERT INTO audit VALUES (?,?,?,?,?,?,?)",
                        (time.time(), level, tag, repr_value(old), repr_value(new), result, message))
        self.db.commit()

    def save_tune(self, zone: int, started: float, before: dict, decided: str) -> None:
        """The gain set before the last TUNE of a zone (a reject after a panel restart still restores it)."""
        self.db.execute("INSERT OR REPLACE INTO tune_sessions VALUES (?,?,?,?)",
                        (zone, started, json.dumps(before), decided))
        self.db.commit()

    def load_tune(self, zone: int) -> tuple[float, dict, str] | None:
        row = self.db.execute("SELECT started, before, decided FROM tune_sessions WHERE zone=?",
                              (zone,)).fetchone()
        return None if row is None else (row[0], json.loads(row[1]), row[2])

    def samples(self, zone: int, since: float, until: float | None = None) -> list[tuple]:
        return self.db.execute(
            "SELECT t, pv, w, y, state, alarm, kp, tn, tv FROM samples WHERE zone=? AND t>=? AND t<=? "
            "ORDER BY t", (zone, since, until if until is not None else time.time() + 1)).fetchall()

    def alarm_events(self, limit: int = 200) -> list[tuple]:
        return self.db.execute(
            "SELECT t, zone, bit, event, text, level FROM alarm_events ORDER BY t DESC, rowid DESC LIMIT ?",
            (limit,)).fetchall()

    def audit(self, limit: int = 200) -> list[tuple]:
        return self.db.execute(
            "SELECT t, level, tag, old, new, result, message FROM audit ORDER BY t DESC, rowid DESC "
            "LIMIT ?", (limit,)).fetchall()

    def prune(self, now: float | None = None, every_s: float = 600.0) -> int:
        """Drop rows past their retention (at most every `every_s`); returns rows removed."""
        now = time.time() if now is None else now
        if now - self._last_prune < every_s:
            return 0
        self._last_prune = now
        removed = 0
        for table, age in (("samples", self.retention.samples_s), ("alarm_events", self.retention.events_s),
                           ("audit", self.retention.events_s)):
            removed += self.db.execute(f"DELETE FROM {table} WHERE t < ?", (now - age,)).rowcount
            removed += self.db.execute(
                f"DELETE FROM {table} WHERE rowid <= (SELECT MAX(rowid) FROM {table}) - ?",
                (self.retention.max_rows,)).rowcount
        self.db.commit()
        return removed


def repr_value(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)
