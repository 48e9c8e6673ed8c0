"""Hostile client: seeded random writes to every writable register of zone 1 (parameters, commands,
process inputs, modes), NaN/inf/huge/out-of-range values, over Modbus on the stepped soft-PLC with the
bundle. After every step (two scans): IDLE/PASSIVE/RESET/ERROR-with-reaction-OFF give output 0 with both
PWM coils off, and no protection is switched off without the engineering unlock (the unlock key is never
written): protected alarm bits neither suppressed nor out of the reaction mask, reaction never NONE.
THERMOST_FUZZ_WRITES sets the number of writes (default 50,000, about 15 s; `make fuzz` runs 1,000,000)."""

from __future__ import annotations

import asyncio
import math
import os
import random

import pytest

from modbus_bridge.client import PlcClient

DEFAULT_WRITES = 50_000
WRITES = int(os.environ.get("THERMOST_FUZZ_WRITES", str(DEFAULT_WRITES)))
WRITES_PER_STEP = 4
SCANS_PER_STEP = 2
PROGRESS_STEPS = 25_000  # a line every 100,000 writes (seen with -s)
SEED = 12
PROTECTED = 0x007C1041  # FB_CtrlParamCheck.dwProtectedAlarms
UNLOCK_KEY = 0x5AFE
SAFE_STATES = {0, 1, 3}  # IDLE, PASSIVE, RESET
STATE_ERROR = 8
REACTION_OFF, REACTION_NONE = 1, 0
SPECIAL = (math.nan, math.inf, -math.inf, 1e38, -1e38, 3.4e38, 0.0, -0.0, 1e-6, -1.0, 32767.5, 1e9)


def random_value(rng: random.Random, tag):
    t = tag.iec_type.upper()
    if t == "BOOL":
        return rng.random() < 0.5
    if t == "REAL":
        if rng.random() < 0.3:
            return rng.choice(SPECIAL)
        lo = tag.meta.min if tag.meta.min is not None else -500.0
        hi = tag.meta.max if tag.meta.max is not None else 500.0
        span = max(hi - lo, 1.0)
        return rng.uniform(lo - span, hi + span)
    if t in ("DWORD", "UDINT"):
        return rng.choice((0, 0xFFFFFFFF, rng.getrandbits(32), 1 << rng.randrange(32)))
    if t == "DINT":
        value = rng.randrange(-(1 << 31), 1 << 31)
        return 0 if value == UNLOCK_KEY else value
    return rng.randrange(-8, 10) if tag.meta.enum else rng.randrange(-32768, 32768)


async def fuzz(regmap, port: int) -> dict:
    rng = random.Random(SEED)
    tags = [t for t in regmap.tags.values() if t.writable and t.name.endswith("Zone1")
            and t.name not in ("nUnlockKeyZone1",)]
    reads = ["fYZone1", "nStateZone1", "dwAlarmSuppZone1", "dwAlarmReactionZone1", "nReactionZone1",
             "bPwmHeatZone1", "bPwmCoolZone1", "fUnlockLeftZone1"]
    counts = {"writes": 0, "steps": 0, "safe_state_steps": 0, "error_steps": 0}
    async with PlcClient("127.0.0.1", port, regmap, name="soft-PLC") as client:
        while counts["writes"] < WRITES:
            writes = {}
            for _ in range(WRITES_PER_STEP):
                tag = rng.choice(tags)
                writes[tag.name] = random_value(rng, tag)
            counts["writes"] += len(writes)
            # two scans: a write is a request the controller checks in the next scan; then the register
            # shows the value in use
            v = await client.exchange(writes, SCANS_PER_STEP, reads)
            counts["steps"] += 1
            if counts["steps"] % PROGRESS_STEPS == 0:
                print(f"write fuzz: {counts['writes']:,} of {WRITES:,} writes", flush=True)
            state, y = int(v["nStateZone1"]), float(v["fYZone1"])
            where = f"step {counts['steps']}, writes {writes}"
            assert math.isfinite(y), where
            assert float(v["fUnlockLeftZone1"]) == 0.0, where
            assert int(v["dwAlarmSuppZone1"]) & PROTECTED == 0, where
            assert int(v["dwAlarmReactionZone1"]) & PROTECTED == PROTECTED, where
            assert int(v["nReactionZone1"]) != REACTION_NONE, where
            off = state in SAFE_STATES or (state == STATE_ERROR and int(v["nReactionZone1"]) == REACTION_OFF)
            if off:
                counts["safe_state_steps" if state in SAFE_STATES else "error_steps"] += 1
                pwm = v["bPwmHeatZone1"] or v["bPwmCoolZone1"]
                assert y == 0.0 and not pwm, f"state {state}: {where}"
    return counts


def test_random_writes_never_give_output_in_a_safe_state_nor_disable_protection(harness):
    if os.environ.get("THERMOST_PLC"):
        pytest.skip("the write fuzz runs on the embedded soft-PLC only (it writes random parameters)")
    from plc.runtime.server import SoftPlc

    async def main() -> dict:
        async with SoftPlc(harness.program_text(), host="127.0.0.1", port=0, stepped=True) as soft:
            return await fuzz(harness.regmap, soft.port)

    counts = asyncio.run(main())
    print(f"write fuzz: {counts}")
    assert counts["safe_state_steps"] > 0 and counts["error_steps"] > 0, counts
