"""Browser tests of the operator panel: `thermost simulate` + `thermost hmi` as child processes, Debian's
Chromium driven by pytest-playwright.

`playwright install` cannot download browsers here: the system Chromium is used (`make browser`
installs it with apt when it can). The binary is THERMOST_CHROMIUM, else the first of CHROMIUM_CANDIDATES
that exists; without one every browser test is skipped with the reason.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM_CANDIDATES = (
    "/usr/lib/chromium/chromium-headless-shell",  # Debian chromium-headless-shell: fastest for tests
    "/usr/lib/chromium/chromium",  # Debian chromium (the real binary; /usr/bin/chromium is a wrapper)
)
SCREEN_DIR = ROOT / "out" / "hmi-screens"
SPEED = 20  # plant and PLC run 20 x real time
ENGINEER_PASSWORD = "test-engineer-pw"
START_TIMEOUT_S = 60.0


def chromium_path() -> str | None:
    env = os.environ.get("THERMOST_CHROMIUM")
    if env:
        return env if Path(env).exists() else None
    for c in CHROMIUM_CANDIDATES:
        if Path(c).exists():
            return c
    return shutil.which("chromium-headless-shell")


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args: dict) -> dict:
    """pytest-playwright has no browser-path option: point it at the system Chromium."""
    path = chromium_path()
    args = dict(browser_type_launch_args)
    if path:
        args["executable_path"] = path
    args["args"] = [*args.get("args", []), "--disable-dev-shm-usage", "--no-sandbox"]
    return args


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTEST_CURRENT_TEST", None)  # NiceGUI would switch into its own test mode
    env["THERMOST_HMI_ENGINEER_PASSWORD"] = ENGINEER_PASSWORD
    env.pop("THERMOST_HMI_OPERATOR_PASSWORD", None)
    return env


@dataclass
class Stack:
    sim: subprocess.Popen
    hmi: subprocess.Popen
    plc_port: int
    url: str
    data_dir: Path

    def sim_command(self, line: str) -> None:
        assert self.sim.stdin is not None
        self.sim.stdin.write(line + "\n")
        self.sim.stdin.flush()

    def read(self, *names: str) -> dict:
        from modbus_bridge.client import PlcClient
        from modbus_bridge.regmap import load_register_map

        async def go() -> dict:
            async with PlcClient("127.0.0.1", self.plc_port, load_register_map()) as c:
                return await c.read_tags(list(names))

        # playwright's sync API keeps an event loop in this thread: the Modbus read runs in another
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            return pool.submit(asyncio.run, go()).result(timeout=10)


def _wait_line(proc: subprocess.Popen, marker: str, timeout: float) -> None:
    assert proc.stdout is not None
    t0 = time.time()
    seen = []
    while time.time() - t0 < timeout:
        line = proc.stdout.readline()
        if not line:
            if proc.poll() is not None:
                break
            continue
        seen.append(line)
        if marker in line:
            return
    raise RuntimeError(f"child did not print {marker!r}: {''.join(seen)[-2000:]}")


def _wait_http(url: str, timeout: float) -> None:
    t0 = time.time()
    while time.time() - t0 < timeout:
        try:
            with urllib.request.urlopen(url, timeout=2) as r:
                if r.status == 200:
                    return
        except OSError:
            time.sleep(0.2)
    raise RuntimeError(f"the panel did not answer at {url}")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def stack(tmp_path_factory) -> Iterator[Stack]:
    if chromium_path() is None:
        pytest.skip("no Chromium (Debian packages chromium / chromium-headless-shell; `make browser` "
                    "installs them as root): browser tests of the panel skipped")
    plc_port, http_port = free_port(), free_port()
    data = tmp_path_factory.mktemp("hmi-data")
    exe = [sys.executable, "-m", "plc.cli"]
    sim = subprocess.Popen([*exe, "simulate", "seed003_hotend_fuzzy", "--speed", str(SPEED), "--port",
                            str(plc_port)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, cwd=ROOT, env=_child_env())
    hmi = None
    try:
        _wait_line(sim, "plant connected", START_TIMEOUT_S)
        threading.Thread(target=sim.stdout.read, daemon=True).start()  # keep the pipe drained
        hmi = subprocess.Popen([*exe, "hmi", "--plc", f"127.0.0.1:{plc_port}", "--port", str(http_port),
                                "--data", str(data)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               text=True, cwd=ROOT, env=_child_env())
        url = f"http://127.0.0.1:{http_port}"
        _wait_http(url + "/diag", START_TIMEOUT_S)
        yield Stack(sim, hmi, plc_port, url, data)
    finally:
        if hmi is not None:
            _stop(hmi)
        _stop(sim)


def shot(page, name: str, docs: bool = False) -> Path:
    """Screenshot as a test artefact (out/hmi-screens/); docs=True with THERMOST_DOCS_SCREENSHOTS=1 also
    refreshes docs/img/ (the screenshots of docs/hmi.md)."""
    SCREEN_DIR.mkdir(parents=True, exist_ok=True)
    path = SCREEN_DIR / f"{name}.png"
    page.screenshot(path=str(path), full_page=False)
    if docs and os.environ.get("THERMOST_DOCS_SCREENSHOTS"):
        (ROOT / "docs" / "img").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, ROOT / "docs" / "img" / f"hmi-{name}.png")
    return path


# pytest-playwright keeps one Playwright (and its event loop in the main thread) for the whole session,
# which breaks every later test that calls asyncio.run(). Here the chain is module-scoped instead: the
# loop is gone when the browser module ends.
@pytest.fixture(scope="module")
def playwright(_pw_api_request_contexts):
    from playwright.sync_api import sync_playwright

    pw = sync_playwright().start()
    if _pw_api_request_contexts:
        _pw_api_request_contexts.instrument(pw)
    yield pw
    pw.stop()


@pytest.fixture(scope="module")
def browser_type(playwright, browser_name: str):
    return getattr(playwright, browser_name)


@pytest.fixture(scope="module")
def launch_browser(browser_type_launch_args: dict, browser_type):
    def launch(**kwargs):
        return browser_type.launch(**{**browser_type_launch_args, **kwargs})

    return launch


@pytest.fixture(scope="module")
def browser(launch_browser):
    b = launch_browser()
    yield b
    b.close()


@pytest.fixture(scope="module")
def browser_context_args(pytestconfig, playwright, device, base_url, _pw_artifacts_folder) -> dict:
    args: dict = {}
    if device:
        args.update(playwright.devices[device])
    if base_url:
        args["base_url"] = base_url
    if pytestconfig.getoption("--video") in ("on", "retain-on-failure"):
        args["record_video_dir"] = _pw_artifacts_folder.name
    return args
