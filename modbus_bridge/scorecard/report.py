"""Scorecard output: markdown table per scenario, an HTML page, a PNG of the overlaid traces (figure.py)."""

from __future__ import annotations

import html
import math
from pathlib import Path

from ..report import slug
from .build import Card, Row
from .figure import write_png

HEADER = (
    "controller",
    "settling 2 % (s)",
    "overshoot (%)",
    "IAE (°C·s)",
    "load recovery (s)",
    "Ms",
    "settling / bound",
    "IAE / best PID",
    "Kp / Tn / Tv",
    "note",
)


def _f(v: float, digits: int = 1) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    if math.isinf(v):
        return "not settled"
    return f"{v:.{digits}f}"


def row_cells(r: Row) -> list[str]:
    g = r.gains
    gains = f"{g.kp:.3g} / {g.tn:.3g} / {g.tv:.3g}" if g is not None else "–"
    return [
        r.name,
        _f(r.settling_s),
        _f(r.overshoot_pct, 2),
        _f(r.iae, 0),
        _f(r.recovery_s),
        _f(r.ms, 2) + (f" ({r.ms_what})" if r.ms_what and math.isfinite(r.ms) else ""),
        _f(r.vs_bound, 2),
        _f(r.vs_best, 2),
        gains,
        r.note,
    ]


def card_markdown(card: Card, png: str | None) -> str:
    sc = card.scenario
    lines = [f"### {sc.name}", "", sc.description, ""]
    if card.skipped:
        return "\n".join([*lines, f"Not scored: {card.skipped}.", ""])
    if sc.reference:
        lines += [f"Paper / source: {sc.reference}", ""]
    where = (
        f"setpoint step {card.step[0]:g} → {card.step[1]:g} °C (phase '{card.scored_phase}')"
        if card.step
        else f"no setpoint step after tuning: from the first load or ramp (phase '{card.scored_phase}')"
    )
    lines += [f"Scored: zone 1 after tuning; {where}; τ = L/(L+T) of the true model {card.tau:.2f}.", ""]
    lines.append("| " + " | ".join(HEADER) + " |")
    lines.append("|" + "---|" * len(HEADER))
    for r in card.rows:
        lines.append("| " + " | ".join(row_cells(r)) + " |")
    if png:
        lines += ["", f"![{sc.name}]({png})"]
    return "\n".join([*lines, ""])


def png_name(card: Card) -> str | None:
    """The file name of the card's PNG; None when nothing was scored."""
    return None if card.skipped or not card.rows else f"scorecard_{slug(card.scenario.name)}.png"


def write_reports(cards: list[Card], out_dir: Path, command: str) -> dict[str, Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    parts = [f"Produced by `{command}`.", ""]
    html_parts = [f"<p>Produced by <code>{html.escape(command)}</code>.</p>"]
    for card in cards:
        png = png_name(card)
        if png:
            write_png(card, out_dir / png)
        parts.append(card_markdown(card, png))
        html_parts.append(card_html(card, png))
    md = out_dir / "scorecard.md"
    md.write_text("# Scorecard\n\n" + "\n".join(parts), encoding="utf-8")
    page = out_dir / "scorecard.html"
    page.write_text(
        "<!doctype html><html><head><meta charset='utf-8'><title>ThermoST scorecard</title>"
        "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:3px 6px;font-size:13px}</style></head><body>"
        "<h1>Scorecard</h1>" + "\n".join(html_parts) + "</body></html>\n",
        encoding="utf-8",
    )
    return {"markdown": md, "html": page}


def card_html(card: Card, png: str | None) -> str:
    sc = card.scenario
    out = [f"<h2>{html.escape(sc.name)}</h2><p>{html.escape(sc.description)}</p>"]
    if card.skipped:
        return "".join(out) + f"<p>Not scored: {html.escape(card.skipped)}.</p>"
    if sc.reference:
        out.append(f"<p>Paper / source: {html.escape(sc.reference)}</p>")
    out.append("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in HEADER) + "</tr>")
    for r in card.rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row_cells(r)) + "</tr>")
    out.append("</table>")
    if png:
        out.append(f"<p><img src='{png}' alt='{html.escape(sc.name)}'></p>")
    return "".join(out)
