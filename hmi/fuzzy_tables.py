"""The fuzzy adapter's shipped rule tables, read from the library source (st_lib/fuzzy/FC_FuzzyPreset*.st),
the same text the PLC runs: no second copy in the panel.

Each preset function holds `aKp`, `aKi`, `aKd : ARRAY[0..48] OF INT := [...]`, rows E = NB .. PB, columns
EC = NB .. PB, consequents -3 (NB) .. 3 (PB). The preset in use is the PLC's nFuzzyPreset register (code =
member order of E_FuzzyPreset). A table changed through the rule mailbox cannot be read back over Modbus:
the page says which preset it shows.
"""

from __future__ import annotations

import re
from pathlib import Path

FUZZY_DIR = Path(__file__).resolve().parents[1] / "st_lib" / "fuzzy"
SETS = 7
OUTPUTS = ("Kp", "Ki", "Kd")
_ARRAY = re.compile(r"\ba(Kp|Ki|Kd)\s*:\s*ARRAY\s*\[\s*0\s*\.\.\s*48\s*\]\s*OF\s+INT\s*:=\s*\[([^\]]*)\]",
                    re.IGNORECASE)
_COMMENT = re.compile(r"\(\*.*?\*\)", re.DOTALL)


def preset_names() -> dict[int, str]:
    """{code: member suffix} of E_FuzzyPreset, e.g. {0: 'TEXTBOOK', 1: 'SEED000', 2: 'SEED003'}."""
    from .model import enum_names

    return enum_names("E_FuzzyPreset", "eFUZZY_PRESET_")


def preset_tables(code: int) -> dict[str, list[list[int]]] | None:
    """{'Kp': 7x7, 'Ki': 7x7, 'Kd': 7x7} of a preset (rows E, columns EC), None when it cannot be read."""
    name = preset_names().get(code)
    if name is None:
        return None
    wanted = name.replace("_", "").lower()
    path = next((p for p in sorted(FUZZY_DIR.glob("FC_FuzzyPreset*.st"))
                 if p.stem.removeprefix("FC_FuzzyPreset").lower() == wanted), None)
    if path is None:
        return None
    text = _COMMENT.sub(" ", path.read_text(encoding="utf-8"))
    out: dict[str, list[list[int]]] = {}
    for m in _ARRAY.finditer(text):
        values = [int(v) for v in m.group(2).replace("\n", " ").split(",") if v.strip()]
        if len(values) != SETS * SETS:
            return None
        out[m.group(1).capitalize()] = [values[r * SETS:(r + 1) * SETS] for r in range(SETS)]
    return out if set(out) == set(OUTPUTS) else None
