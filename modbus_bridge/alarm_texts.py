"""Alarm-bit texts and error-id texts, read from the library's reference (docs/library.md), the same
source the library documents them in: the panel keeps no second copy.

Alarm table rows look like `| 0 | 16#0000_0001 | sensor open: ... |`, `| 1–5 | ... | a, b, c, d, e (...) |`
or `| 8 / 9 | ... | text 8 / text 9 |`; the error-id table `| 10 | TUNE: ... |`.
"""

from __future__ import annotations

import re
from pathlib import Path

LIBRARY_DOC = Path(__file__).resolve().parents[1] / "docs" / "library.md"
_BIT_RANGE = re.compile(r"^(\d+)\s*[–-]\s*(\d+)$")
_BIT_PAIR = re.compile(r"^(\d+)\s*/\s*(\d+)$")
MAX_TEXT = 160


def _clean(text: str) -> str:
    text = re.sub(r"`", "", text).strip()
    return text if len(text) <= MAX_TEXT else text[: MAX_TEXT - 1].rstrip() + "…"


def _section(doc: str, heading: str) -> list[str]:
    lines = doc.splitlines()
    try:
        start = next(i for i, ln in enumerate(lines) if ln.startswith("#") and heading in ln)
    except StopIteration:
        return []
    out = []
    for ln in lines[start + 1 :]:
        if ln.startswith("#"):
            break
        out.append(ln)
    return out


def alarm_texts(path: Path = LIBRARY_DOC) -> dict[int, str]:
    """{bit: text} from the alarm table of the library reference ({} when the file is missing)."""
    try:
        doc = path.read_text(encoding="utf-8")
    except OSError:
        return {}
    texts: dict[int, str] = {}
    for ln in _section(doc, "Alarms"):
        cells = [c.strip() for c in ln.strip().strip("|").split("|")]
        if len(cells) < 3 or not cells[0] or not cells[0][0].isdigit():
            continue
        bits, condition = cells[0], cells[2]
        if m := _BIT_RANGE.match(bits):
            lo, hi = int(m.group(1)), int(m.group(2))
            parts = [p.strip() for p in re.sub(r"\(.*\)", "", condition).split(",")]
            if len(parts) == hi - lo + 1:
                texts.update({lo + k: _clean(p) for k, p in enumerate(parts)})
            else:
                texts.update({b: _clean(condition) for b in range(lo, hi + 1)})
        elif m := _BIT_PAIR.match(bits):
            parts = [p.strip() for p in condition.split(" / ")]
            for k, b in enumerate((int(m.group(1)), int(m.group(2)))):
                texts[b] = _clean(parts[k] if len(parts) == 2 else condition)
        elif bits.isdigit():
            texts[int(bits)] = _clean(condition)
    return texts


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
