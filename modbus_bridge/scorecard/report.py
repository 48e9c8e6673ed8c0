"""Scorecard output: markdown table per scenario, an HTML page, a PNG of the overlaid traces."""

from __future__ import annotations

import html
import math
from pathlib import Path

from ..report import slug
from .build import Card, Row, trace_window

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


def write_png(card: Card, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, axu) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, height_ratios=(2, 1))
    end = 0.0
    for r in card.rows:
        if r.outcome is None:
            continue
        t, pv, u = trace_window(r.outcome, card.scored_phase)
        ax.plot(t, pv, lw=1.1, label=r.name)
        axu.plot(t, u, lw=0.9)
        end = max(end, float(t[-1]) if t.size else 0.0)
    if card.bound is not None:
        b = card.bound
        ax.plot(b.t, b.y, "k--", lw=1.2, label="bound (bang-hold)")
        u_b = [b.u_full if x < b.switch_s else b.u_hold for x in b.t]
        axu.plot(b.t, u_b, "k--", lw=1.0)
        r0 = card.step[1]
        band = 0.02 * abs(card.step[1] - card.step[0])
        ax.axhspan(r0 - band, r0 + band, color="0.85", zorder=0, label="±2 % band")
    ax.set_xlim(0.0, end if end > 0 else None)
    ax.set_ylabel("PV (°C)")
    what = (f"from the step (phase '{card.scored_phase}')" if card.step
            else f"from the first load or ramp (phase '{card.scored_phase}')")
    ax.set_title(f"{card.scenario.name}: zone 1 {what}", fontsize=10)
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    axu.set_ylabel("controller output (%)")
    axu.set_xlabel("t (s)")
    axu.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_reports(cards: list[Card], out_dir: Path, command: str) -> dict[str, Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    parts = [f"Produced by `{command}`.", ""]
    html_parts = [f"<p>Produced by <code>{html.escape(command)}</code>.</p>"]
    for card in cards:
        png = None
        if not card.skipped and card.rows:
            png = f"scorecard_{slug(card.scenario.name)}.png"
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
