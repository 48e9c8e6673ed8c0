"""Progress tells the truth: one named line/bar per variant, total = the planned plant time (an event phase
counts at its timeout until the event comes), 100 % at the end of a completed run; plain lines without
carriage returns when stderr is not a terminal; library log lines only with -v."""

from __future__ import annotations

import asyncio
import io
import logging
from pathlib import Path

from modbus_bridge.binding import ControllerCodes
from modbus_bridge.progress import CountProgress, RunProgress, quiet_libraries
from modbus_bridge.regmap import load_register_map
from modbus_bridge.runner import HarnessSetup, run_variants
from modbus_bridge.scenario import Variant, load_scenario

FIXTURES = Path(__file__).parent / "harness_fixtures"
PROGRAM = (FIXTURES / "p_harness_test.st").read_text(encoding="utf-8")


def test_total_is_the_plan_and_a_completed_run_ends_at_100_percent():
    import dataclasses

    sc = load_scenario(FIXTURES / "small_fopdt.toml")
    sc = dataclasses.replace(sc, variants=[Variant("first"), Variant("second")])
    setup = HarnessSetup(regmap=load_register_map(sources=[("p.st", PROGRAM)]), codes=ControllerCodes.load(),
                         program=PROGRAM)
    seen: dict[int, list[tuple[float, float]]] = {0: [], 1: []}
    asyncio.run(run_variants(sc, setup, progress_for=lambda i: lambda d, t: seen[i].append((d, t))))
    for calls in seen.values():
        first_total = calls[0][1]
        done, total = calls[-1]
        assert first_total == sc.nominal_duration_s  # tuning counted at its 60 s timeout
        assert done == total < first_total  # the fixture "tunes" in 10 s: the plan shrank, 100 % reached
        assert all(d <= t + 1e-9 for d, t in calls)


def test_plain_lines_when_not_a_terminal():
    stream = io.StringIO()
    with RunProgress(["fuzzy PID", "PID"], stream=stream, terminal=False) as p:
        p.update(0, 5.0, 100.0)
        p.update(1, 5.0, 100.0)
        p.update(0, 50.0, 100.0)  # within PLAIN_EVERY_S of the last line: not printed
        p.update(0, 80.0, 80.0)
        p.update(1, 80.0, 80.0)
    text = stream.getvalue()
    assert "\r" not in text and "\x1b" not in text
    assert text.splitlines() == [
        "thermost: fuzzy PID: 5/100 s plant time (5 %)",
        "thermost: PID: 5/100 s plant time (5 %)",
        "thermost: fuzzy PID: 80/80 s plant time (100 %)",
        "thermost: PID: 80/80 s plant time (100 %)",
    ]


def test_rich_bar_reaches_100_percent():
    stream = io.StringIO()
    with RunProgress(["fuzzy PID"], stream=stream, terminal=True) as p:
        p.update(0, 10.0, 1210.0)
        p.update(0, 395.0, 395.0)
        task = p._progress.tasks[0]  # type: ignore[union-attr]
        assert task.description == "fuzzy PID" and task.percentage == 100.0


def test_library_logs_only_with_verbose():
    quiet_libraries(False)
    assert not logging.getLogger("pymodbus").isEnabledFor(logging.ERROR)
    quiet_libraries(True)
    assert logging.getLogger("pymodbus").isEnabledFor(logging.ERROR)
    quiet_libraries(False)


def test_counted_progress_plain_lines_end_with_the_total_and_the_note():
    stream = io.StringIO()
    with CountProgress("optimise seed003", total=3, unit="experiments", stream=stream, terminal=False) as bar:
        for j in (3.0, 2.0, 2.5):
            bar.advance(note=f"best J {j}")
    lines = stream.getvalue().splitlines()
    assert lines[-1] == "thermost: optimise seed003: 3/3 experiments, best J 2.5"
    assert "\r" not in stream.getvalue()


def test_counted_progress_draws_a_bar_on_a_terminal_and_nothing_when_quiet():
    stream = io.StringIO()
    with CountProgress("scorecard", total=2, unit="scenarios", stream=stream, terminal=True) as bar:
        bar.describe("seed003_hotend_fuzzy")
        bar.advance()
        bar.advance()
    assert "2/2" in stream.getvalue() and "scorecard" in stream.getvalue()
    quiet = io.StringIO()
    with CountProgress("scorecard", total=2, unit="scenarios", enabled=False, stream=quiet,
                       terminal=False) as bar:
        bar.advance()
    assert quiet.getvalue() == ""
