"""Panel figures for `thermost bench`: Modbus requests per poll cycle (2 zones), poll-to-browser latency
(median, p95), panel server CPU per open trend tab at 10 Hz, trend update rate in the browser.

Runs `thermost simulate` (default scenario, real time) and `thermost hmi --rate 10` as child processes and
opens trend tabs in the system Chromium (headless). Latency is the time from the completed Modbus read
(the sample's timestamp) to its arrival in the page's chart buffer, on the same machine clock. CPU is the
panel process' user + system time over a window with 0 tabs and with N tabs open.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

RATE_HZ = 10.0
CLI = "import sys; from plc.cli import main; sys.exit(main(sys.argv[1:]))"
CHROMIUM = ("/usr/lib/chromium/chromium-headless-shell", "/usr/lib/chromium/chromium")


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _wait_http(url: str, timeout: float = 60.0) -> None:
    t0 = time.time()
    while time.time() - t0 < timeout:
        try:
            with urllib.request.urlopen(url, timeout=2):
                return
        except OSError:
            time.sleep(0.2)
    raise RuntimeError(f"the panel did not answer at {url}")


def requests_per_cycle() -> tuple[int, int, int]:
    """(fast requests per poll cycle, registers/coils read, tags) for all zones of the application."""
    from modbus_bridge.client import plan_reads
    from modbus_bridge.regmap import load_register_map

    from .model import load_model

    model = load_model(load_register_map())
    spans = plan_reads([model.regmap[n] for n in model.fast_tags()])
    return len(spans), sum(s.count for s in spans), len(model.fast_tags())


def browser_figures(url: str, hmi_pid: int, tabs: int, window_s: float) -> dict:
    from playwright.sync_api import sync_playwright

    exe = next((c for c in CHROMIUM if Path(c).exists()), None)
    if exe is None:
        raise RuntimeError("no Chromium (make browser)")
    out: dict = {}
    c0 = _cpu_s(hmi_pid)
    time.sleep(window_s)
    out["cpu_idle_pct"] = (_cpu_s(hmi_pid) - c0) / window_s * 100
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=["--disable-dev-shm-usage", "--no-sandbox"])
        pages = []
        for _ in range(tabs):
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.goto(url + "/trend?zone=1")
            pages.append(page)
        cids = [pg.get_by_test_id("trend-chart").get_attribute("id").lstrip("c") for pg in pages]
        time.sleep(3.0)  # first contact (ring buffer backlog) done
        first = [pg.evaluate(f"thermost.stats({cid})") for pg, cid in zip(pages, cids, strict=True)]
        c0, t0 = _cpu_s(hmi_pid), time.time()
        time.sleep(window_s)
        c1, t1 = _cpu_s(hmi_pid), time.time()
        last = [pg.evaluate(f"thermost.stats({cid})") for pg, cid in zip(pages, cids, strict=True)]
        browser.close()
    lat: list[float] = []
    rows = draws = 0
    for a, b in zip(first, last, strict=True):
        lat += b["lat"][len(a["lat"]):] if len(b["lat"]) >= len(a["lat"]) else b["lat"]
        rows += b["received"] - a["received"]
        draws += b["draws"] - a["draws"]
    wall = t1 - t0
    lat.sort()
    out.update(
        cpu_tabs_pct=(c1 - c0) / wall * 100,
        lat_median_ms=statistics.median(lat) if lat else float("nan"),
        lat_p95_ms=lat[min(len(lat) - 1, int(0.95 * len(lat)))] if lat else float("nan"),
        rows_per_s=rows / wall / tabs,
        draws_per_s=draws / wall / tabs,
    )
    out["cpu_per_tab_pct"] = (out["cpu_tabs_pct"] - out["cpu_idle_pct"]) / tabs
    return out


def run(quick: bool) -> None:
    print("operator panel (hmi):")
    n, words, tags = requests_per_cycle()
    print(f"  Modbus requests per poll cycle (2 zones, {tags} live tags, {words} registers/coils): {n}")
    tabs, window = (1, 5.0) if quick else (2, 10.0)
    plc_port, http_port = _free_port(), _free_port()
    env = dict(os.environ)
    env.pop("PYTEST_CURRENT_TEST", None)
    with tempfile.TemporaryDirectory() as data:
        sim = subprocess.Popen([sys.executable, "-c", CLI, "simulate", "--port", str(plc_port)],
                               stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               env=env)
        hmi = None
        try:
            time.sleep(3.0)
            hmi = subprocess.Popen([sys.executable, "-c", CLI, "hmi", "--plc", f"127.0.0.1:{plc_port}",
                                    "--port", str(http_port), "--data", data, "--rate", str(RATE_HZ)],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
            url = f"http://127.0.0.1:{http_port}"
            _wait_http(url + "/diag")
            f = browser_figures(url, hmi.pid, tabs, window)
        except Exception as exc:  # noqa: BLE001 - a bench reports what it could not measure
            print(f"  browser figures not measured: {type(exc).__name__}: {exc}")
            return
        finally:
            for proc in (hmi, sim):
                if proc is not None and proc.poll() is None:
                    proc.terminate()
                    proc.wait(timeout=10)
    load = os.getloadavg()[0]
    print(f"  (machine load average {load:.1f} on {os.cpu_count()} cores during the measurement)")
    print(f"  poll-to-browser latency at {RATE_HZ:g} Hz ({tabs} trend tab(s), {window:g} s): median "
          f"{f['lat_median_ms']:.0f} ms, p95 {f['lat_p95_ms']:.0f} ms (goal p95 < 300 ms)")
    print(f"  panel server CPU: {f['cpu_idle_pct']:.1f} % with no tab (poll loop), "
          f"{f['cpu_tabs_pct']:.1f} % with {tabs} tab(s): {f['cpu_per_tab_pct']:.1f} % per tab (goal <= 5 %)")
    print(f"  trend update rate per tab: {f['rows_per_s']:.1f} samples/s received, {f['draws_per_s']:.1f} "
          f"redraws/s (goal >= 5 Hz)")
