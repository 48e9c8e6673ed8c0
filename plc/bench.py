"""`thermost bench` / `make bench`: benchmark figures (printed, never asserted).

1. scans per CPU second of the soft-PLC on the conformance PID case and on the largest program
   the project ships (the bundle: library + application); CPU time, so a busy machine does not
   lower the figure;
   and the CPU time of loading the bundle: the first load in a process (parse, generate, compile) against
   the next (the compiled code kept: a harness loads it for its reference copy and for every soft-PLC);
2. wall time of 6,000 stepped scans with one Modbus write and one read per scan over
   loopback (soft-PLC in a separate process, as a harness sees it), in three request styles;
3. figures of the other packages: `modbus_bridge.bench.run(quick)`, `plc.bench_adapter.run(quick)`,
   `plc.bench_heatup.run(quick)`, `plc.bench_tunefit.run(quick)`, `plc.tuning_study.run(quick)`.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from plc.runtime.rawclient import RawModbusClient

ROOT = Path(__file__).resolve().parents[1]
STEPPED_SCANS = 6000
STEPPED_SCANS_QUICK = 1000
TARGET_STEPPED_S = 3.0
SCAN_BUDGET_S = 2.0
SCAN_BUDGET_QUICK_S = 0.5
WARMUP_SCANS = 300
PID_CASE = "pid_plant"
LOAD_RESOLUTION_S = 1e-6  # a kept load faster than the CPU clock shows still gives a ratio
START_TIMEOUT_S = 60
STOP_TIMEOUT_S = 10
OUTPUT_WORDS = 8
DEFAULT_IO_ADDRESS = 2048  # %MD0
CLI_SNIPPET = "import sys; from plc.cli import main; sys.exit(main())"  # `-m plc.cli` would duplicate classes
EXTERNAL_BENCHES = (
    "modbus_bridge.bench", "plc.bench_adapter", "plc.bench_heatup", "plc.bench_tunefit", "plc.tuning_study",
)


def conformance_dir() -> Path | None:
    """../shared/conformance (or $THERMOST_SHARED/conformance) when present."""
    env = os.environ.get("THERMOST_SHARED")
    candidates = [Path(env)] if env else []
    candidates += [ROOT.parent / "shared", ROOT / "shared"]
    for candidate in candidates:
        if (candidate / "conformance").is_dir():
            return candidate / "conformance"
    return None


def scans_per_second(load: Callable[[], object], budget_s: float, warmup: int = 0) -> tuple[float, int]:
    """(scans per CPU second, scans) over about `budget_s` of CPU time. warmup = 0: a fresh application
    every 200 scans (for a program that does its work in its first scans, like the conformance cases);
    warmup > 0: one application, `warmup` untimed scans (first-scan initialisation, tables built over the
    first cycles), then the steady state."""
    app = load()
    for _ in range(warmup):
        app.scan()  # type: ignore[attr-defined]
    scans = 0
    elapsed = 0.0
    while elapsed < budget_s:
        if not warmup and scans:
            app = load()
        start = time.process_time()
        for _ in range(200):
            app.scan()  # type: ignore[attr-defined]
        elapsed += time.process_time() - start
        scans += 200
    return scans / elapsed, scans


def _loader(filename: str, text: str) -> Callable[[], object]:
    from plc.st.compiler import load_application

    return lambda: load_application([(filename, text)])


def scan_rates(quick: bool) -> list[tuple[str, float | None, str]]:
    """(program, scans per CPU second or None, note) for the conformance PID case and the bundle."""
    budget = SCAN_BUDGET_QUICK_S if quick else SCAN_BUDGET_S
    rows: list[tuple[str, float | None, str]] = []
    folder = conformance_dir()
    if folder is None:
        rows.append(("conformance pid_plant", None, "skipped: conformance corpus not found"))
    else:
        path = folder / f"{PID_CASE}.st"
        rate, n = scans_per_second(_loader(str(path), path.read_text()), budget)
        rows.append(("conformance pid_plant", rate, f"{n} scans"))
    from plc.bundle import bundle_text

    text = bundle_text()
    if "CONFIGURATION" not in text.upper():
        rows.append(("bundle", None, "skipped: the bundle has no CONFIGURATION"))
        return rows
    try:
        rate, n = scans_per_second(_loader("<bundle>", text), budget, WARMUP_SCANS)
    except Exception as exc:  # noqa: BLE001 - a benchmark reports, it does not fail
        rows.append(("bundle", None, f"skipped: {type(exc).__name__}: {exc}"))
        return rows
    lines = len(text.splitlines())
    rows.append((f"bundle ({lines:,} lines of ST)", rate,
                 f"{n} scans, steady state after {WARMUP_SCANS} scans"))
    return rows


def load_costs() -> tuple[float, float]:
    """CPU seconds of loading the bundle the first time in this process and of loading it again."""
    from plc.bundle import bundle_text
    from plc.st.compiler import load_application

    # a comment no earlier load had, so the first load compiles the program as a new process would
    text = bundle_text() + f"\n(* load cost {time.time_ns()} *)\n"
    costs = []
    for _ in range(2):
        start = time.process_time()
        load_application([("<bundle>", text)])
        costs.append(time.process_time() - start)
    return costs[0], costs[1]


def bench_scan_rates(quick: bool) -> None:
    for name, rate, note in scan_rates(quick):
        if rate is None:
            print(f"scan rate, {name}: {note}")
        else:
            print(f"scan rate, {name}: {rate:,.0f} scans per CPU second ({note})")
    first, again = load_costs()
    print(f"loading the bundle: {first:.3f} s CPU the first time in a process, {again:.3f} s again "
          f"({first / max(again, LOAD_RESOLUTION_S):.0f} x)")


def _bench_program() -> tuple[Path, str]:
    """The bundle when it has a CONFIGURATION, else the conformance PID case."""
    from plc.bundle import bundle_text

    text = bundle_text()
    if "CONFIGURATION" in text.upper():
        handle = tempfile.NamedTemporaryFile("w", suffix=".st", delete=False)
        with handle:
            handle.write(text)
        return Path(handle.name), "bundle"
    folder = conformance_dir()
    if folder is None:
        raise FileNotFoundError("neither a bundle with a CONFIGURATION nor the conformance corpus")
    return folder / f"{PID_CASE}.st", "conformance pid_plant"


def _start_plc(path: Path) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen(
        [sys.executable, "-c", CLI_SNIPPET, "plc", str(path), "--stepped", "--port", "0"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )
    line = proc.stdout.readline() if proc.stdout else ""
    match = re.search(r"listening on [\d.]+:(\d+)", line)
    if not match:
        proc.kill()
        proc.wait(STOP_TIMEOUT_S)
        raise RuntimeError(f"soft-PLC did not start: {line!r}")
    return proc, int(match.group(1))


def stepped_round_trips(quick: bool) -> tuple[str, int, list[tuple[str, float, int]], str]:
    """(program, scans per style, [(request style, wall s, scans that ran)], fault note): wall time, since
    the round trips cross two processes and the kernel."""
    n = STEPPED_SCANS_QUICK if quick else STEPPED_SCANS
    path, label = _bench_program()
    proc, port = _start_plc(path)
    try:
        with RawModbusClient("127.0.0.1", port) as client:
            address = DEFAULT_IO_ADDRESS  # words read first and written back unchanged
            words = client.read_holding(address, 2)
            styles = {
                "FC16 write + FC6 step + FC3 read (3 round trips)": lambda: (
                    client.write_registers(address, words), client.step(1),
                    client.read_holding(address, OUTPUT_WORDS)),
                "FC16 write + FC23 step&read (2 round trips)": lambda: (
                    client.write_registers(address, words),
                    client.step_and_read(1, address, OUTPUT_WORDS)),
                "FC23 write&read with RW_STEPS=1 (1 round trip)": lambda: client.read_write(
                    address, OUTPUT_WORDS, address, words),
            }
            rows: list[tuple[str, float, int]] = []
            for name, iteration in styles.items():
                client.set_rw_steps(1 if "RW_STEPS" in name else 0)
                before = client.status().scan_count
                start = time.perf_counter()
                for _ in range(n):
                    iteration()
                elapsed = time.perf_counter() - start
                rows.append((name, elapsed, client.status().scan_count - before))
            status = client.status()
            note = f"the program faulted during the bench: {status.fault_text}" if status.faulted else ""
            return label, n, rows, note
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(STOP_TIMEOUT_S)
        if label == "bundle":
            path.unlink(missing_ok=True)


def bench_stepped(quick: bool) -> None:
    label, n, rows, note = stepped_round_trips(quick)
    for name, elapsed, ran in rows:
        met = "met" if elapsed < TARGET_STEPPED_S else "MISSED"
        verdict = "" if quick else f" (target < {TARGET_STEPPED_S:g} s: {met})"
        print(f"stepped, {label}, {n} scans [{name}]: {elapsed:.2f} s, "
              f"{1e6 * elapsed / n:.0f} us/scan, {ran} scans ran{verdict}")
    if note:
        print(f"  note: {note}")


def run_external(quick: bool) -> None:
    for module_name in EXTERNAL_BENCHES:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name and module_name.startswith(exc.name):
                print(f"{module_name}: not available")
                continue
            raise
        print(f"--- {module_name}")
        module.run(quick)


def main_bench(args: argparse.Namespace) -> int:
    quick = bool(getattr(args, "quick", False))
    print(f"ThermoST bench ({'quick' if quick else 'full'}; figures only, nothing asserted)")
    bench_scan_rates(quick)
    bench_stepped(quick)
    run_external(quick)
    return 0

