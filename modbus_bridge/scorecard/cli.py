"""`thermost scorecard [SCENARIO...] [--quick] [-o DIR] [--markdown FILE]`."""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path
from typing import TYPE_CHECKING

from plc.cli import UserError

if TYPE_CHECKING:
    from .build import Card


QUICK_SCENARIOS = ("seed003_hotend_fuzzy",)
QUICK_EVALS = 6
FULL_EVALS = 30
IMAGE_DIR = "img"  # beside the markdown file given to --markdown
BLOCK = re.compile(r"(<!-- figures:scorecard -->\n).*?(<!-- /figures:scorecard -->)", re.DOTALL)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "scenarios",
        nargs="*",
        metavar="SCENARIO",
        help="scenario files or shipped names (default: every shipped scenario; with --quick: seed 003)",
    )
    p.add_argument("--quick", action="store_true", help=f"CI mode: {QUICK_EVALS} optimiser experiments")
    p.add_argument(
        "--evals",
        type=int,
        default=None,
        metavar="N",
        help=f"optimiser experiments per scenario (default {FULL_EVALS}, --quick {QUICK_EVALS})",
    )
    p.add_argument("-o", "--out", metavar="DIR", default="out/scorecard", help="report directory")
    p.add_argument(
        "--markdown",
        metavar="FILE",
        help=f"also put the tables into FILE's figures block, with their PNGs in {IMAGE_DIR}/ beside FILE",
    )
    p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=None, metavar="N", help="local worker processes")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def command_line(args: argparse.Namespace) -> str:
    parts = ["thermost scorecard", *args.scenarios]
    if args.quick:
        parts.append("--quick")
    if args.evals is not None:
        parts += ["--evals", str(args.evals)]
    return " ".join(parts)


def cards_markdown(cards: list[Card], command: str, pngs: dict[str, str] | None = None) -> str:
    """The block's text; `pngs`: scenario name -> the path of its PNG relative to the markdown file."""
    from .report import card_markdown

    pngs = pngs or {}
    return f"Produced by `{command}`.\n\n" + "\n".join(
        card_markdown(c, pngs.get(c.scenario.name)) for c in cards
    )


def quick_markdown(page_dir: Path) -> str:
    """The `figures:scorecard` block: `thermost scorecard --quick` (the docs producer), its figures drawn
    into IMAGE_DIR of `page_dir`."""
    from ..optimise.executor import make_executor
    from ..scenario import load_scenario, resolve_scenario
    from .build import build_card

    with make_executor() as executor:
        scenarios = [load_scenario(resolve_scenario(n)) for n in QUICK_SCENARIOS]
        cards = [build_card(sc, executor, QUICK_EVALS) for sc in scenarios]
    return cards_markdown(cards, "thermost scorecard --quick", draw_figures(cards, page_dir))


def draw_figures(cards: list[Card], page_dir: Path) -> dict[str, str]:
    """Each scored card's PNG drawn into IMAGE_DIR of `page_dir`; scenario name -> path relative to it."""
    from .report import png_name, write_png

    pngs = {}
    for card in cards:
        name = png_name(card)
        if name:
            write_png(card, page_dir / IMAGE_DIR / name)
            pngs[card.scenario.name] = f"{IMAGE_DIR}/{name}"
    return pngs


def update_markdown(path: Path, cards: list[Card], command: str) -> None:
    """The tables into FILE's figures block, each with its PNG, drawn into IMAGE_DIR beside FILE."""
    body = cards_markdown(cards, command, draw_figures(cards, path.parent))
    text = path.read_text(encoding="utf-8") if path.exists() else ""
    block = f"<!-- figures:scorecard -->\n{body}<!-- /figures:scorecard -->"
    if BLOCK.search(text):
        text = BLOCK.sub(lambda _m: block, text)
    else:
        text = (text.rstrip() + "\n\n" if text else "# Scorecard\n\n") + block + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")


def main_scorecard(args: argparse.Namespace) -> int:
    from ..client import PlcError
    from ..optimise.executor import ExecutorError, make_executor
    from ..progress import CountProgress
    from ..scenario import ScenarioError, load_scenario, resolve_scenario, shipped_scenarios
    from .build import Card, build_card
    from .report import card_markdown, write_reports

    evals = args.evals if args.evals is not None else (QUICK_EVALS if args.quick else FULL_EVALS)
    if evals < 4:
        raise UserError(f"--evals must be >= 4 (the starting simplex), got {evals}")
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers must be >= 1, got {args.workers}")
    names = args.scenarios or (list(QUICK_SCENARIOS) if args.quick else [p.stem for p in shipped_scenarios()])
    try:
        scenarios = [load_scenario(resolve_scenario(n)) for n in names]
    except ScenarioError as exc:
        raise UserError(str(exc)) from None
    try:
        executor = make_executor(args.scheduler, args.workers)
    except ExecutorError as exc:
        raise UserError(str(exc)) from None
    t0 = time.perf_counter()
    cards = []
    with (
        executor,
        CountProgress("scorecard", total=len(scenarios), unit="scenarios", enabled=not args.quiet) as bar,
    ):
        for sc in scenarios:
            bar.describe(sc.name)
            try:
                cards.append(build_card(sc, executor, evals))
            except PlcError as exc:
                raise UserError(str(exc)) from None
            except ValueError as exc:  # e.g. a plant that cannot be held at the setpoint
                card = Card(sc, skipped=f"cannot be scored: {exc}")
                cards.append(card)
            bar.advance()
    command = command_line(args)
    written = write_reports(cards, Path(args.out), command)
    for card in cards:
        print(card_markdown(card, None))
    if args.markdown:
        update_markdown(Path(args.markdown), cards, command)
    print(
        f"report: {written['markdown']} and {written['html']} (PNG beside them); "
        f"{time.perf_counter() - t0:.1f} s on {executor.name}"
    )
    return 0
