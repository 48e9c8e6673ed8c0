"""`thermost optimise`: Nelder-Mead on the PID set of zone 1 over closed-loop experiments."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from plc.cli import UserError

COST_CHOICES = ("iae", "itae", "ramp")  # experiment.COSTS (not imported here: `thermost --help` stays fast)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="scenario .toml file or shipped name")
    p.add_argument("--cost", choices=COST_CHOICES, default="iae", help="cost to minimise (default iae)")
    p.add_argument("--max-overshoot", type=float, default=2.0, metavar="PCT", help="overshoot limit, %%")
    p.add_argument("--max-ms", type=float, default=2.0, metavar="MS", help="max sensitivity limit")
    p.add_argument("--seed", type=int, default=None, metavar="N", help="noise seed of every experiment")
    p.add_argument("--evals", type=int, default=40, metavar="N", help="closed-loop experiments (default 40)")
    p.add_argument("--plc", metavar="HOST:PORT", help="run the experiments on this PLC (one at a time)")
    p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="local worker processes")
    p.add_argument("-o", "--output", metavar="FILE", default="params.json", help="parameter set JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _check(args: argparse.Namespace) -> None:
    if args.evals < 1:
        raise UserError(f"--evals must be >= 1, got {args.evals}")
    if not (args.max_overshoot >= 0.0 and math.isfinite(args.max_overshoot)):
        raise UserError(f"--max-overshoot must be a finite number >= 0, got {args.max_overshoot}")
    if not (args.max_ms > 1.0 and math.isfinite(args.max_ms)):
        raise UserError(f"--max-ms must be a finite number > 1 (Ms >= 1 always), got {args.max_ms}")
    if args.seed is not None and args.seed < 0:
        raise UserError(f"--seed must be >= 0, got {args.seed}")
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers must be >= 1, got {args.workers}")
    if args.plc and args.scheduler:
        raise UserError("--plc and --scheduler exclude each other (one PLC runs one experiment at a time)")
    if args.plc:
        from ..runner import parse_host_port

        try:
            parse_host_port(args.plc)
        except ValueError as exc:
            raise UserError(str(exc)) from None


def main_optimise(args: argparse.Namespace) -> int:
    from ..client import PlcError
    from ..progress import CountProgress
    from ..scenario import ScenarioError, load_scenario, resolve_scenario
    from .executor import ExecutorError, make_executor
    from .search import Optimiser, Settings

    _check(args)
    try:
        scenario = load_scenario(resolve_scenario(args.scenario))
    except ScenarioError as exc:
        raise UserError(str(exc)) from None
    settings = Settings(
        cost=args.cost,
        max_overshoot_pct=args.max_overshoot,
        max_ms=args.max_ms,
        seed=args.seed,
        evals=args.evals,
        plc=args.plc,
    )
    t0 = time.perf_counter()
    try:
        executor = make_executor(args.scheduler, args.workers, serial=bool(args.plc))
    except ExecutorError as exc:
        raise UserError(str(exc)) from None
    try:
        opt = Optimiser(scenario, settings, executor)
    except ValueError as exc:
        executor.close()
        raise UserError(f"{scenario.name}: {exc}") from None
    bar = CountProgress(f"optimise {scenario.name}", total=args.evals, unit="experiments",
                        enabled=not args.quiet)
    best = [math.inf]

    def on_eval(ev) -> None:
        best[0] = min(best[0], ev.objective)
        bar.advance(note=f"best J {best[0]:.4g}")

    opt.on_eval = on_eval
    try:
        with executor, bar:
            result = opt.run()
    except PlcError as exc:
        raise UserError(str(exc)) from None
    b = result.best
    doc = {
        "scenario": scenario.name,
        "zone": scenario.zones[0].plc_zone,
        "cost": settings.cost,
        "cost_value": b.cost,
        "objective": b.objective,
        "overshoot_pct": b.overshoot_pct,
        "ms": b.ms,
        "max_overshoot_pct": settings.max_overshoot_pct,
        "max_ms": settings.max_ms,
        "seed": scenario.seed if settings.seed is None else settings.seed,
        "evaluations": len(result.history),
        "executor": executor.name,
        "settle_s": result.settle_s,
        "parameters": b.gains.as_dict(),
        "registers": _registers(scenario.zones[0], b.gains),
        "start": {
            **result.start.gains.as_dict(),
            "cost_value": result.start.cost,
            "objective": result.start.objective,
            "ms": result.start.ms,
        },
    }
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    g = b.gains
    print(
        f"{scenario.name}: Kp {g.kp:.4g} %/°C, Tn {g.tn:.4g} s, Tv {g.tv:.4g} s (Td {g.td_s:.4g} s); "
        f"{settings.cost} {b.cost:.4g}, overshoot {b.overshoot_pct:.2f} %, Ms {b.ms:.2f} "
        f"(start: {settings.cost} {result.start.cost:.4g}, Ms {result.start.ms:.2f}); "
        f"{len(result.history)} experiments on {executor.name} in {time.perf_counter() - t0:.1f} s -> {out}"
    )
    return 0


def _registers(zone, gains) -> dict[str, float]:
    from .experiment import gain_writes, tunes_cooling

    return gain_writes(zone.plc_zone, gains, cooling=tunes_cooling(zone))
