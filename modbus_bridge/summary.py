"""summary.md / summary.html of a run: the verdict first, then what was run and how, then the figures.

Order: title; PARTIAL REPORT banner when the run did not complete; the verdict table (each judged metric
vs the paper and vs the goal, pass/fail); the variants overlaid on one axis; how it was made (command,
tool version, date, plant parameters, sensor, identified plant, measured noise, tuned gains and filter per
variant, the fuzzy adapter's Ms bound); all metrics side by side; one plot per variant. Both files are
rendered from the same blocks.
"""

from __future__ import annotations

import datetime as dt
import html
from dataclasses import dataclass, field
from pathlib import Path

from . import kept_values
from .analysis import PhaseMetrics
from .loop import RunResult
from .verdict import verdict_rows, verdict_table

TUNED_KEYS = kept_values.columns(kept_values.TUNED)  # metric key -> label with unit
# the fuzzy adapter's Ms bound per variant and phase -> label
ADAPTER_COLUMNS = kept_values.columns(kept_values.ADAPTER)


@dataclass
class Block:
    kind: str  # "h2", "p", "banner", "table", "img", "list"
    text: str = ""
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)


def tool_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return f"thermost {version('thermost')}"
    except PackageNotFoundError:
        return "thermost (not installed)"


def _tuned_table(runs: list[tuple[RunResult, list[PhaseMetrics]]]) -> Block | None:
    header = ["variant", "zone", "phase", *[label for _, label in TUNED_KEYS]]
    rows = []
    for result, pms in runs:
        for pm in pms:
            if pm.kind == "tune":
                cells = [f"{pm.values[k]:.4g}" if k in pm.values else "–" for k, _ in TUNED_KEYS]
                rows.append([result.variant.name, pm.zone, pm.phase, *cells])
    return Block("table", header=header, rows=rows) if rows else None


def _adapter_table(runs: list[tuple[RunResult, list[PhaseMetrics]]]) -> Block | None:
    """The fuzzy adapter's Ms bound in the phases it ran in (none: no fuzzy variant, or no bound in use)."""
    header = ["variant", "zone", "phase", *[label for _, label in ADAPTER_COLUMNS]]
    rows = []
    for result, pms in runs:
        for pm in pms:
            if "fuzzy_ms_reachable" in pm.values:
                v = pm.values
                rows.append([result.variant.name, pm.zone, pm.phase, f"{v['fuzzy_ms_reachable']:.4g}",
                             f"{v['fuzzy_ms_max']:.3g}" if "fuzzy_ms_max" in v else "–",
                             f"{v['fuzzy_gain_scale']:.3g}" if "fuzzy_gain_scale" in v else "–",
                             f"{100.0 * v['fuzzy_box_share']:.0f} %" if "fuzzy_box_share" in v else "–"])
    return Block("table", header=header, rows=rows) if rows else None


def summary_blocks(runs: list[tuple[RunResult, list[PhaseMetrics]]], metrics_header: list[str],
                   metrics_rows: list[list[str]], *, partial: str | None, compare_png: str | None,
                   command: str | None, plots: dict[str, str]) -> list[Block]:
    scenario = runs[0][0].scenario
    blocks = [Block("h1", scenario.name)]
    if partial:
        blocks.append(Block("banner", f"PARTIAL REPORT - the run did not complete ({partial}); the figures "
                                      "below are what was measured until then."))
    blocks.append(Block("p", scenario.description))
    rows = verdict_rows(runs)
    blocks.append(Block("h2", "Verdict"))
    if rows:
        passed = sum(r.passed for r in rows)
        blocks.append(Block("p", f"{passed} of {len(rows)} judged figures meet their goal."))
        header, body = verdict_table(rows)
        blocks.append(Block("table", header=header, rows=body))
    else:
        blocks.append(Block("p", "No figure of this scenario is judged (no [[target]] and no identification "
                                 "of a plant with known parameters)."))
    if compare_png:
        blocks += [Block("h2", "Variants compared"), Block("img", compare_png)]
    elif any(r.interrupted for r, _ in runs):
        blocks.append(Block("p", "No plots: the run was interrupted; the CSV traces hold every sample."))
    made = [
        f"command: `{command}`" if command else "command: (library call)",
        f"tool: {tool_version()}",
        f"date: {dt.datetime.now(dt.UTC).isoformat(timespec='seconds')}",
        f"scenario file: {scenario.path}",
        f"reference: {scenario.reference or '–'}",
        f"plant: {scenario.plant_model} " + ", ".join(f"{k} = {v}" for k, v in scenario.plant_params.items()),
        f"plant step: {scenario.dt_s:g} s, {scenario.scans_per_step} PLC scan(s) per step, PV path "
        f"{scenario.pv_path}, output {scenario.output_path}, seed {scenario.seed}",
    ]
    for zone in scenario.zones:
        s = zone.sensor
        made.append(f"zone {zone.name} (PLC zone {zone.plc_zone}): sensor {s.adc.kind}, noise "
                    f"{s.noise_sigma_c:g} °C, lag {s.lag_s:g} s")
    for result, _ in runs:
        status = f"error: {result.error}" if result.error else "completed"
        mode = "real time" if result.realtime else "stepped"
        made.append(f"variant {result.variant.name}: {status}; {result.plant_time_s:.0f} s of plant time in "
                    f"{result.wall_s:.2f} s wall ({result.steps} steps, {mode})")
    blocks += [Block("h2", "How this report was made"), Block("list", rows=[[m] for m in made])]
    tuned = _tuned_table(runs)
    if tuned is not None:
        blocks += [Block("h2", "Identified plant and tuned gains"), tuned]
    adapter = _adapter_table(runs)
    if adapter is not None:
        blocks += [Block("h2", "Fuzzy adapter: Ms over the gain sets it can reach"),
                   Block("p", "Worst maximum sensitivity over every gain set the adapter can reach, on the "
                              "identified model with the filter in use (fFuzzyMsReachable), kept at or below "
                              "the bound by scaling the base gains and narrowing the ratio box."),
                   adapter]
    blocks += [Block("h2", "All metrics"), Block("table", header=metrics_header, rows=metrics_rows)]
    for name, png in plots.items():
        blocks += [Block("h2", f"Trace: {name}"), Block("img", png)]
    return blocks


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|")


def render_markdown(blocks: list[Block]) -> str:
    out: list[str] = []
    for b in blocks:
        if b.kind == "h1":
            out += [f"# {b.text}", ""]
        elif b.kind == "h2":
            out += [f"## {b.text}", ""]
        elif b.kind == "banner":
            out += [f"> **{b.text.split(' - ', 1)[0]}** - {b.text.split(' - ', 1)[1]}", ""]
        elif b.kind == "p":
            out += [b.text, ""]
        elif b.kind == "list":
            out += [f"- {row[0]}" for row in b.rows] + [""]
        elif b.kind == "table":
            out += ["| " + " | ".join(map(_md_cell, b.header)) + " |", "|" + "---|" * len(b.header)]
            out += ["| " + " | ".join(map(_md_cell, r)) + " |" for r in b.rows] + [""]
        elif b.kind == "img":
            out += [f"![{Path(b.text).stem}]({b.text})", ""]
    return "\n".join(out)


def render_html(blocks: list[Block], title: str) -> str:
    parts: list[str] = []
    for b in blocks:
        if b.kind in ("h1", "h2", "p"):
            parts.append(f"<{b.kind}>{html.escape(b.text)}</{b.kind}>")
        elif b.kind == "banner":
            head, rest = b.text.split(" - ", 1)
            parts.append(f"<p class='banner'><strong>{html.escape(head)}</strong> - {html.escape(rest)}</p>")
        elif b.kind == "list":
            parts.append("<ul>" + "".join(f"<li>{html.escape(r[0])}</li>" for r in b.rows) + "</ul>")
        elif b.kind == "table":
            head = "".join(f"<th>{html.escape(h)}</th>" for h in b.header)
            body = "".join(
                "<tr>" + "".join(f"<td class='{_css(c)}'>{html.escape(c)}</td>" for c in r) + "</tr>"
                for r in b.rows
            )
            parts.append(f"<table><tr>{head}</tr>{body}</table>")
        elif b.kind == "img":
            parts.append(f"<p><img src='{html.escape(b.text)}' alt='{html.escape(Path(b.text).stem)}'></p>")
    style = ("table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}"
             ".pass{background:#d8f0d8}.FAIL{background:#f6d0d0}.banner{background:#fff0c0;padding:6px}"
             "img{max-width:100%}")
    return (f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{style}</style></head><body>{''.join(parts)}</body></html>\n")


def _css(cell: str) -> str:
    return cell if cell in ("pass", "FAIL") else ""
