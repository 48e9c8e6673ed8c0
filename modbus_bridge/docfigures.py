"""Figures in docs/*.md come from code: `thermost docs` (`make docs`) rewrites every block

    <!-- figures:NAME -->
    ...generated markdown...
    <!-- /figures:NAME -->

with `PRODUCERS[NAME]()`. Register a producer with `@producer("name")` (a function returning markdown);
`measured=True` marks figures that depend on the machine (timings): `make docs` rewrites them, the test
`tests/test_docfigures.py` does not compare them. Every other block must be what its producer returns
today: the test fails when docs and code disagree. A block naming no producer is an error.
`thermost docs --check` reports stale blocks without writing (exit 1).
"""

from __future__ import annotations

import argparse
import asyncio
import functools
import json
import os
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BLOCK = re.compile(r"(<!-- figures:([\w.-]+) -->\n)(.*?)(<!-- /figures:\2 -->)", re.DOTALL)
MEASURED_OPENPLC = DOCS / "measured" / "openplc.json"

PRODUCERS: dict[str, Callable[[], str]] = {}
MEASURED: set[str] = set()


def producer(name: str, *, measured: bool = False):
    def register(fn: Callable[[], str]) -> Callable[[], str]:
        PRODUCERS[name] = fn
        if measured:
            MEASURED.add(name)
        return fn

    return register


def tests_on_path() -> None:
    """Producers that show what a test computes import it from tests/; `thermost docs` (a console
    script) does not put the checkout on sys.path."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))


# ---- producers ----------------------------------------------------------------------------------
@functools.cache
def default_run() -> list:
    """The default scenario, every variant, stepped (deterministic: same figures on every machine)."""
    from .runner import HarnessSetup, run_variants
    from .scenario import load_scenario, resolve_scenario

    return asyncio.run(run_variants(load_scenario(resolve_scenario(None)), HarnessSetup.default()))


def _phase(pms, name: str):
    return next((pm for pm in pms if pm.phase == name), None)


@producer("seed003-results")
def seed003_results() -> str:
    from .verdict import verdict_rows

    runs = default_run()
    scenario = runs[0][0].scenario
    p = scenario.plant_params
    lines = [f"Default scenario `{scenario.name}`, stepped (deterministic), `thermost run`:", ""]
    tune = _phase(runs[0][1], "tune")
    if tune is not None:
        v = tune.values
        lines.append(
            f"- Tuning identifies Ks {v['identified_ks_c_per_pct']:.3f} °C/% "
            f"(plant {p['gain_c_per_pct']:g}), "
            f"Tu {v['identified_tu_s']:.1f} s ({p['dead_time_s']:g}), Tg {v['identified_tg_s']:.1f} s "
            f"({p['time_constant_s']:g}) in {v['tuning_duration_s']:.0f} s; gains Kp "
            f"{v['tuned_kp_pct_per_c']:.2f} %/°C, Tn {v['tuned_tn_s']:.1f} s, Tv {v['tuned_tv_s']:.2f} s"
            + (f", Ms {v['tuned_ms']:.1f} on the identified model." if "tuned_ms" in v else ".")
        )
    for result, pms in runs:
        step, load = _phase(pms, "step"), _phase(pms, "load")
        if step is None or load is None:
            continue
        s, ld = step.values, load.values
        lines.append(
            f"- {result.variant.name}: step 160→200 °C overshoot {s['overshoot_pct']:.2f} %, 2 % settling "
            f"{s['settling_time_2pct_s']:.1f} s, IAE {s['iae_c_s']:.0f} °C·s; load step: max deviation "
            f"{ld['max_deviation_c']:.2f} °C, recovery (2 %) {ld['recovery_time_2pct_s']:.1f} s."
        )
    rows = verdict_rows(runs)
    lines.append(f"- Verdict: {sum(r.passed for r in rows)} of {len(rows)} judged figures meet their goal "
                 f"(the paper's fuzzy PID: 5 % overshoot, 60 s settling, 23 s recovery).")
    return "\n".join(lines) + "\n"


@producer("harness-bench", measured=True)
def harness_bench() -> str:
    from .bench import DEFAULT_TARGET_S, default_run_wall, plant_costs, scenario_speed
    from .scenario import shipped_scenarios

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    costs = plant_costs(2000)
    timed = default_run_wall()
    speeds = []
    for path in shipped_scenarios():
        try:
            w, plant_s, _, _ = scenario_speed(path.stem)
            speeds.append(f"{path.stem} {plant_s / w:.0f}×")
        except Exception as exc:  # noqa: BLE001 - a figure that cannot be measured says so
            speeds.append(f"{path.stem} not measured ({type(exc).__name__})")
    return (
        f"Measured by `make docs` on {os.cpu_count()} cores, load average {load:.1f} at the start:\n\n"
        "- Plant integration per step (dt 0.1 s): "
        + ", ".join(f"{name} {us:.1f} µs" for name, us in costs.items())
        + ".\n"
        "- `thermost run` (default scenario, all its variants in parallel, reports): "
        f"{timed.wall_s:.1f} s wall (median of {timed.spread}; target < {DEFAULT_TARGET_S:g} s: "
        f"{'met' if timed.wall_s < DEFAULT_TARGET_S else 'MISSED'}), {timed.cpu_s:.1f} s CPU, exit code "
        f"{timed.code}.\n"
        "- Speed-up over real time, first variant, stepped, including start-up: " + ", ".join(speeds) + ".\n"
    )


@functools.cache
def adapter_cost_rows() -> list[tuple[str, float | None, str]]:
    """FB_FuzzyGainAdapter per call in the soft-PLC, measured once per `make docs` (two pages show it)."""
    from plc.bench_adapter import adapter_costs

    return adapter_costs(quick=False)


@producer("softplc-bench", measured=True)
def softplc_bench() -> str:
    """docs/softplc.md: scan rates (CPU time), stepped round trips (wall time), fuzzy adapter per call."""
    from plc.bench import TARGET_STEPPED_S, load_costs, scan_rates, stepped_round_trips

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    rows = ["| figure | value |", "|---|---|"]
    for name, rate, note in scan_rates(quick=False):
        value = note if rate is None else f"{rate:,.0f} scans per CPU second ({1e6 / rate:.0f} µs per scan)"
        rows.append(f"| soft-PLC in-process, {name} | {value} |")
    first, again = load_costs()
    rows.append(f"| loading the bundle, first in a process (parse, generate, compile) | {first:.2f} s CPU |")
    rows.append(f"| loading the bundle again in that process (compiled code kept) | {again:.3f} s CPU |")
    label, n, stepped, note = stepped_round_trips(quick=False)
    for style, elapsed, _ in stepped:
        met = "met" if elapsed < TARGET_STEPPED_S else "MISSED"
        target = f" (target < {TARGET_STEPPED_S:g} s: {met})" if style.startswith("FC16 write + FC6") else ""
        rows.append(f"| {n:,} stepped scans of the {label}, {style} | {elapsed:.2f} s wall, "
                    f"{1e6 * elapsed / n:.0f} µs per scan{target} |")
    for mode, cost, status in adapter_cost_rows():
        value = status if cost is None else f"{cost:,.0f} µs per call ({cost / 100:.1f} % of a 10 ms cycle)"
        rows.append(f"| FB_FuzzyGainAdapter, {mode} | {value} |")
    tail = f"\n\nNote: {note}\n" if note else "\n"
    return (f"Measured by `make docs` on {os.cpu_count()} cores, load average {load:.1f} at the start "
            "(scan rates in CPU time; round trips in wall time):\n\n" + "\n".join(rows) + tail)


@producer("openplc-scan")
def openplc_scan() -> str:
    """The scan time recorded on a real OpenPLC v3 runtime (docs/measured/openplc.json)."""
    m = json.loads(MEASURED_OPENPLC.read_text(encoding="utf-8"))
    scan = m["scan_us"]
    return (
        f"Measured on a real OpenPLC v3 runtime ({m['source']}): the bundle's scan at its "
        f"{m['task_ms']} ms task takes {scan['min']}/{scan['avg']}/{scan['max']} µs min/avg/max, wake-up "
        f"latency ≤ {m['wakeup_latency_ms']} ms, runtime CPU {m['cpu_pct']} %; seed 003 at "
        f"{m['seed003_speed']}× matches the soft-PLC within {m['seed003_match_pct']} % on the step.\n"
    )


@producer("scorecard", measured=True)
def scorecard() -> str:
    """docs/scorecard.md: the quick scorecard (optimiser experiments: rewritten by `make docs` only), its
    figure drawn into docs/img."""
    from .scorecard.cli import quick_markdown

    return quick_markdown(DOCS)


# ---- the block machinery ------------------------------------------------------------------------
def blocks(text: str) -> list[tuple[str, str]]:
    """(name, current body) of every figures block of a page."""
    return [(m.group(2), m.group(3)) for m in BLOCK.finditer(text)]


def render(text: str, names: set[str] | None = None, cache: dict[str, str] | None = None) -> str:
    """The page with the blocks named in `names` (all when None) regenerated."""
    cache = {} if cache is None else cache

    def one(m: re.Match) -> str:
        name = m.group(2)
        if name not in PRODUCERS:
            raise KeyError(f"no producer registered for figures:{name} (modbus_bridge/docfigures.py)")
        if names is not None and name not in names:
            return m.group(0)
        if name not in cache:
            cache[name] = PRODUCERS[name]().rstrip("\n") + "\n"
        return m.group(1) + cache[name] + m.group(4)

    return BLOCK.sub(one, text)


def pages() -> list[Path]:
    return sorted(DOCS.glob("*.md"))


def main_docs(args: argparse.Namespace) -> int:
    from plc.cli import UserError

    from .cli import schema_text

    names = set(args.only) if args.only else None
    if names is None and args.skip_measured:
        names = set(PRODUCERS) - MEASURED
    unknown = (names or set()) - set(PRODUCERS)
    if unknown:
        known = ", ".join(sorted(PRODUCERS))
        raise UserError(f"no producer named {', '.join(sorted(unknown))} (known: {known})")
    stale: list[str] = []
    cache: dict[str, str] = {}
    for page in pages():
        text = page.read_text(encoding="utf-8")
        try:
            new = render(text, names, cache)
        except KeyError as exc:
            raise UserError(f"{page.relative_to(ROOT)}: {exc.args[0]}") from None
        if new != text:
            stale.append(str(page.relative_to(ROOT)))
            if not args.check:
                page.write_text(new, encoding="utf-8")
    schema = DOCS / "scenario.schema.json"
    current = schema.read_text(encoding="utf-8") if schema.exists() else ""
    if current != schema_text():
        stale.append(str(schema.relative_to(ROOT)))
        if not args.check:
            schema.write_text(schema_text(), encoding="utf-8")
    verb = "stale" if args.check else "rewritten"
    print(f"{len(stale)} file(s) {verb}" + (f": {', '.join(stale)}" if stale else ""))
    return 1 if stale and args.check else 0


from . import docfigures_fuzzy, docfigures_library  # noqa: E402, F401 - register their pages' producers
