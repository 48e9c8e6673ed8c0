"""`thermost run` fails well: a PLC lost mid-run gives exit 1 and a report of what was measured, marked
partial; SIGINT ends the run within 2 s with a partial report; SIGINT and SIGTERM leave no worker
process behind. Real processes, as a user runs them."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

CLI = "import sys; from plc.cli import main; sys.exit(main())"
STOP_LIMIT_S = 2.0


def thermost(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", CLI, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, **kw)


def children_of(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


class StderrLines:
    """Collects a process' stderr lines in a thread (the progress lines tell when a run is running)."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.lines: list[str] = []
        self._thread = threading.Thread(target=self._read, args=(proc,), daemon=True)
        self._thread.start()

    def _read(self, proc: subprocess.Popen) -> None:
        for line in proc.stderr:  # type: ignore[union-attr]
            self.lines.append(line)

    def text(self) -> str:
        self._thread.join(timeout=5)
        return "".join(self.lines)


def wait_for_progress(proc: subprocess.Popen, err: StderrLines, timeout_s: float = 120.0) -> None:
    """Until every variant reported plant time (plain progress lines: stderr is not a terminal)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if sum("s plant time" in line for line in err.lines) >= 2:
            time.sleep(0.5)  # the workers are running their scenario
            return
        assert proc.poll() is None, err.text()
        time.sleep(0.05)
    pytest.fail("the run reported no progress")


def assert_partial_report(out: Path) -> None:
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert "PARTIAL REPORT" in summary.splitlines()[2], summary[:300]
    doc = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    assert doc["complete"] is False and doc["partial_reason"]
    assert any(v["run"]["plant_time_s"] > 0 for v in doc["variants"]), "nothing measured"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc to find the worker processes")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_ends_run_and_workers_with_partial_report(tmp_path, sig):
    out = tmp_path / "report"
    proc = thermost("run", "--out", str(out))
    lines = StderrLines(proc)
    wait_for_progress(proc, lines)
    workers = children_of(proc.pid)
    assert len(workers) >= 2, workers
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    took = time.monotonic() - t0
    err = lines.text()
    assert took <= STOP_LIMIT_S, f"ended {took:.2f} s after {sig.name}"
    assert proc.returncode == 130, (proc.returncode, err)
    assert "Traceback" not in err, err
    assert re.search(r"interrupted by SIG(INT|TERM): partial report", err), err
    time.sleep(0.2)
    alive = [pid for pid in workers if Path(f"/proc/{pid}").exists()
             and "Z" not in Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[:1]]
    assert not alive, f"worker processes left running: {alive}"
    assert_partial_report(out)


def test_plc_lost_mid_run_gives_exit_1_and_a_partial_report(tmp_path):
    plc = thermost("plc", "--port", "0", "--stepped")
    try:
        line = plc.stdout.readline()
        port = int(re.search(r":(\d+) ", line).group(1))
        out = tmp_path / "report"
        run = thermost("run", "--plc", f"127.0.0.1:{port}", "--out", str(out))
        lines = StderrLines(run)
        deadline = time.monotonic() + 120
        while not any("s plant time" in line for line in lines.lines) and time.monotonic() < deadline:
            assert run.poll() is None, lines.text()
            time.sleep(0.05)
        time.sleep(0.3)  # the first variant is running
        plc.kill()
        run.wait(timeout=60)
        err = lines.text()
    finally:
        for p in (plc, locals().get("run")):
            if p is not None and p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
    assert run.returncode == 1, (run.returncode, err)
    assert "Traceback" not in err, err
    assert "partial report" in err.strip().splitlines()[-1], err
    assert_partial_report(out)
