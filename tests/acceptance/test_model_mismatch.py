"""Model mismatch over Modbus: the zone tunes on the nominal plant, then the plant's time constant T and
dead time L change by -30 % / +30 % (the identified model the heater monitor uses is off by that much) and
a nominal programme runs (hold, setpoint 20 degC down and back, load step). Goal: 0 trips and 0 latched
warnings, so no alarm bit at all and never state ERROR. CI runs two cases; THERMOST_SLOW=1 runs every
combination on seed 003 and T1."""

from __future__ import annotations

import asyncio
import os

import pytest

from modbus_bridge.alarms import describe
from modbus_bridge.faults import run_mismatch
from tests.slow_cases import skip_unless_slow

from .conftest import PLC_ENV, STATE_ERROR, alarm_word

PLANTS = ("seed003_hotend_fuzzy", "t1_rrf_hotend")
SCALES = ((0.7, 0.7), (1.3, 1.3), (0.7, 1.3), (1.3, 0.7))
QUICK = {("seed003_hotend_fuzzy", (0.7, 0.7)), ("t1_rrf_hotend", (1.3, 1.3))}
BAND_BITS = 0xF00  # tolerance-band warnings (FB_CtrlAlarms bits 8-11)
# goals not met yet (expected failures with THERMOST_SLOW=1): only the band warning is excused, a trip fails
SHORTFALLS = {
    ("seed003_hotend_fuzzy", (0.7, 1.3)): (
        "L/T grows from 0.45 to 0.84 and the self-tuned PID goes into a limit cycle of about +-8 degC "
        "(period about 36 s): the band warning is real; the loop needs more robust gains, not a quieter alarm"
    ),
}


class BandWarning(AssertionError):
    """The loop left its tolerance band (a latched warning), with no trip."""


def cases():
    for plant in PLANTS:
        for scale in SCALES:
            marks = [] if (plant, scale) in QUICK else [pytest.mark.slow]
            why = SHORTFALLS.get((plant, scale))
            if why:
                marks.append(pytest.mark.xfail(reason=f"known shortfall: {why}", raises=BandWarning,
                                               strict=True))
            yield pytest.param(plant, scale, marks=marks, id=f"{plant}-T{scale[0]}-L{scale[1]}")


@pytest.mark.parametrize(("plant", "scale"), list(cases()))
def test_model_mismatch_raises_no_alarm(harness, plant, scale):
    if (plant, scale) not in QUICK:
        skip_unless_slow(f"{plant} T x{scale[0]} L x{scale[1]}")
    run = asyncio.run(run_mismatch(plant, scale[0], scale[1], harness, plc=os.environ.get(PLC_ENV)))
    assert run.tuned, f"{plant}: the zone did not tune"
    assert run.t and run.t[-1] >= run.t_fault + 700.0, f"{plant}: the programme did not run to its end"
    word = alarm_word(run.alarm)
    first = run.detection_s()
    where = f"{plant} T x{scale[0]} L x{scale[1]}: {describe(word)}, first {first} s after the change"
    assert STATE_ERROR not in run.state, f"{where}; state ERROR"
    assert word & ~BAND_BITS == 0, where
    if word:
        raise BandWarning(where)
