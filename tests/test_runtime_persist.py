"""OpenPLC's persistent-storage rules in the soft-PLC store: %MW/%MD/%ML kept bit for bit; %QW and coils
not; a value saved as zero keeps its initial value; a foreign file is refused."""

from __future__ import annotations

import json
import threading

import pytest

from plc.runtime.image import ModbusImage
from plc.runtime.persist import PersistentStore, PersistError
from plc.runtime.server import load_program

PROGRAM = """
PROGRAM P
  VAR
    nW AT %MW3 : INT := 7;
    fD AT %MD4 : REAL := 1.5;
    fL AT %ML2 : LREAL := 2.5;
    nZero AT %MW4 : INT := 9;
    nQ AT %QW1 : INT := 5;
    bC AT %QX0.1 : BOOL;
  END_VAR
  nW := nW;
END_PROGRAM
CONFIGURATION C RESOURCE R ON PLC TASK t(INTERVAL := T#100ms, PRIORITY := 0); PROGRAM i WITH t : P;
END_RESOURCE END_CONFIGURATION
"""


def fresh():
    app = load_program(PROGRAM)
    return app, {v.name.upper(): v for v in app.located}, ModbusImage(app.located)


def test_kept_and_not_kept(tmp_path):
    app, var, image = fresh()
    var["NW"].set(-12)
    var["FD"].set(0.1)
    var["FL"].set(1e-300)
    var["NZERO"].set(0)
    var["NQ"].set(99)
    var["BC"].set(True)
    store = PersistentStore(tmp_path / "p.json", image, threading.Lock())
    assert store.save_if_changed() and not store.save_if_changed()  # saved once, then nothing changed
    app2, var2, image2 = fresh()
    assert PersistentStore(tmp_path / "p.json", image2, threading.Lock()).restore() == 3
    assert var2["NW"].get() == -12
    assert var2["FD"].get() == var["FD"].get()  # the REAL bit for bit
    assert var2["FL"].get() == 1e-300
    assert var2["NZERO"].get() == 9  # saved as zero: initial value kept (OpenPLC)
    assert var2["NQ"].get() == 5 and var2["BC"].get() is False  # %QW and coils are not kept


def test_blank_and_foreign_store(tmp_path):
    _, var, image = fresh()
    assert PersistentStore(tmp_path / "none.json", image, threading.Lock()).restore() == 0
    assert var["NW"].get() == 7
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "something else"}), encoding="utf-8")
    with pytest.raises(PersistError, match="not a persistent-storage file"):
        PersistentStore(bad, image, threading.Lock()).restore()
