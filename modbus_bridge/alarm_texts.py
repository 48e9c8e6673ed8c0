"""Alarm-bit texts (from FB_CtrlAlarms.st's header, through modbus_bridge.alarms) and error-id texts (from
the error-id table of the library reference docs/library.md, rows `| 10 | TUNE: ... |`): the panel and the
exports keep no second copy.
"""

from __future__ import annotations

import re
from pathlib import Path

from .alarms import alarm_bits

LIBRARY_DOC = Path(__file__).resolve().parents[1] / "docs" / "library.md"
MAX_TEXT = 160


def _clean(text: str) -> str:
    text = re.sub(r"`", "", text).strip()
    return text if len(text) <= MAX_TEXT else text[: MAX_TEXT - 1].rstrip() + "…"


def alarm_texts() -> dict[int, str]:
    """{bit: text} of the alarm word, from the header of FB_CtrlAlarms.st (modbus_bridge.alarms), the
    source docs/library.md's alarm table is generated from."""
    return {b.bit: _clean(b.text) for b in alarm_bits().values()}


def error_texts(path: Path = LIBRARY_DOC) -> dict[int, str]:
    """{nErrorId: meaning} from the error-id table of the library reference."""
    try:
        doc = path.read_text(encoding="utf-8")
    except OSError:
        return {}
    out: dict[int, str] = {}
    in_table = False
    for ln in doc.splitlines():
        if ln.startswith("| nErrorId"):
            in_table = True
            continue
        if in_table:
            cells = [c.strip() for c in ln.strip().strip("|").split("|")]
            if not ln.startswith("|"):
                break
            if len(cells) >= 2 and cells[0].isdigit():
                out[int(cells[0])] = _clean(cells[1])
    return out


def describe_bits(word: int, texts: dict[int, str]) -> list[tuple[int, str]]:
    return [(b, texts.get(b, f"alarm bit {b}")) for b in range(32) if word >> b & 1]
