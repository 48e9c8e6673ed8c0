"""Handlers of the harness sub-commands (see commands.py)."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from plc.cli import UserError, writable_file

from .regmap import RegisterMapError, load_register_map, markdown
from .scenario import ScenarioError, load_scenario, resolve_scenario, shipped_scenarios

OUT_DIR = Path("out")
INTERRUPTED_EXIT = 130  # as a shell reports a process ended by SIGINT


def schema_text() -> str:
    import json

    from .scenario_schema import json_schema

    return json.dumps(json_schema(), indent=2, sort_keys=True) + "\n"


def write_output(name: str, text: str) -> None:
    output = writable_file(name)
    try:
        output.parent.mkdir(parents=True, exist_ok=True)
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UserError(f"{output}: cannot write: {exc.strerror or exc}") from None


def main_scenarios(args: argparse.Namespace) -> int:
    if getattr(args, "schema", False):
        if args.output:
            write_output(args.output, schema_text())
        else:
            sys.stdout.write(schema_text())
        return 0
    if getattr(args, "output", None):
        raise UserError("-o needs --schema")
    for path in shipped_scenarios():
        try:
            sc = load_scenario(path)
        except ScenarioError as exc:
            print(f"{path.stem:34s} INVALID: {exc}")
            continue
        print(f"{path.stem:34s} {sc.description}")
    return 0


def main_regmap(args: argparse.Namespace) -> int:
    try:
        regmap = load_register_map()
    except RegisterMapError as exc:
        raise UserError(str(exc)) from None
    if args.markdown:
        text = markdown(regmap)
    else:
        lines = [
            f"{t.address:5d} {t.table:17s} {t.location:8s} {t.iec_type:6s} {t.name:28s} {t.comment}"
            for t in sorted(regmap.tags.values(), key=lambda t: (t.table, t.address))
        ]
        text = "\n".join(lines) + "\n"
    if args.output:
        write_output(args.output, text)
    else:
        sys.stdout.write(text)
    return 0


def command_line() -> str:
    """The command as the user typed it (for the report)."""
    import shlex

    return "thermost " + " ".join(shlex.quote(a) for a in sys.argv[1:])


def check_out_dir(out_dir: Path) -> None:
    """The report directory: an existing directory or one that can be made (never a file)."""
    existing = next((p for p in (out_dir, *out_dir.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        what = "the report directory" if existing == out_dir else f"{existing} (in the path)"
        raise UserError(f"--out {out_dir}: {what} is a file, expected a directory")
    if not os.access(existing, os.W_OK):
        raise UserError(f"--out {out_dir}: {existing} is not writable")


def main_run(args: argparse.Namespace) -> int:
    from .analysis import run_metrics
    from .client import PlcError
    from .preflight import check_bindings
    from .progress import RunProgress, quiet_libraries
    from .report import slug, summary_rows, text_table, write_reports
    from .runner import FleetJob, HarnessSetup, parse_host_port, run_fleet, run_variants
    from .workers import run_async_interruptible, run_variants_parallel

    t_start = time.perf_counter()
    try:
        scenario = load_scenario(resolve_scenario(args.scenario))
    except ScenarioError as exc:
        raise UserError(str(exc)) from None
    if args.speed != 1.0 and not args.plc:
        raise UserError(
            "--speed N needs a PLC whose TASK interval was shortened N times (use --plc HOST:PORT); "
            "the embedded soft-PLC runs the bundle's own interval"
        )
    plcs = args.plc or []
    for address in plcs:
        try:
            parse_host_port(address)
        except ValueError as exc:
            raise UserError(str(exc)) from None
    if len(plcs) > 1 and len(plcs) != len(scenario.variants):
        raise UserError(
            f"{len(plcs)} PLCs for {len(scenario.variants)} variant(s): give one --plc, or one per "
            f"variant ({', '.join(v.name for v in scenario.variants)})"
        )
    try:
        setup = HarnessSetup.default()
        check_bindings(
            scenario, setup.bindings(scenario), setup.codes, setup.regmap, stepped=not args.realtime
        )
    except RegisterMapError as exc:
        raise UserError(str(exc)) from None
    out_dir = Path(args.out) if args.out else OUT_DIR / slug(scenario.name)
    check_out_dir(out_dir)
    quiet_libraries(getattr(args, "verbose", False))
    names = [v.name for v in scenario.variants]
    if len(plcs) > 1:
        names = [f"{v.name} @ {address}" for v, address in zip(scenario.variants, plcs, strict=True)]
    stop_reason: str | None = None
    try:
        with RunProgress(names, enabled=not args.quiet) as progress:
            if len(plcs) > 1:  # variant i on PLC i, all at once (side by side on real hardware)
                jobs = [FleetJob(scenario, address, i) for i, address in enumerate(plcs)]
                results = run_async_interruptible(lambda stop: run_fleet(jobs, setup, speed=args.speed))
                runs = [(r, run_metrics(r) if r.zones and r.zones[0].t else []) for r in results]
            elif plcs or args.realtime:
                runs = run_async_interruptible(
                    lambda stop: run_variants(
                        scenario,
                        setup,
                        plc=plcs[0] if plcs else None,
                        realtime=args.realtime,
                        speed=args.speed,
                        progress_for=progress.callback,
                        should_stop=stop,
                    )
                )
            else:  # embedded stepped soft-PLC: controller variants side by side in parallel processes
                runs = run_variants_parallel(
                    scenario, setup, progress_for=progress.callback, plot_dir=out_dir
                )
    except PlcError as exc:
        raise UserError(str(exc)) from None
    except RegisterMapError as exc:
        raise UserError(str(exc)) from None
    if any(r.interrupted for r, _ in runs):
        stop_reason = next(r.error for r, _ in runs if r.interrupted)
    written = write_reports(runs, out_dir, command=command_line())
    header, rows = summary_rows(runs)
    print(text_table(header, rows))
    for result, _ in runs:
        mode = "real time" if result.realtime else "stepped"
        line = (
            f"{result.variant.name}: {result.plant_time_s:.0f} s plant time, {result.steps} steps, "
            f"{result.wall_s:.2f} s wall ({mode}, {result.plant_time_s / max(result.wall_s, 1e-9):.0f}x)"
        )
        if result.jitter_ms:
            jit = sorted(abs(j) for j in result.jitter_ms)
            line += f", jitter median {jit[len(jit) // 2]:.2f} ms, max {jit[-1]:.2f} ms"
        print(line)
    print(
        f"report: {written['summary_md']} (metrics.json, CSV and PNG beside it); "
        f"total {time.perf_counter() - t_start:.2f} s"
    )
    if stop_reason is not None:
        sys.stderr.write(f"thermost: {stop_reason}: partial report in {out_dir}\n")
        return INTERRUPTED_EXIT
    errors = [r.error for r, _ in runs if r.error]
    if errors:
        sys.stderr.write(f"thermost: {errors[0]} (partial report of what was measured in {out_dir})\n")
        return 1
    return 0
