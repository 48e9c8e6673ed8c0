"""Reports of a scenario run: CSV trace, PNG plot, metrics.json, markdown + HTML summary.

Layout under the output directory (default out/<scenario name>/):
  trace_<variant>.csv    one row per plant step and zone
  plot_<variant>.png     PV, setpoint, output and effective gains per zone (matplotlib, Agg backend)
  metrics.json           {"scenario", "variants": [{"name", "error", "run", "phases": [...]}]}, one
                         object per zone and phase; metric names carry their unit (metrics.py)
  summary.md / .html     tables with the controller variants side by side
"""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

from . import kept_values
from .analysis import PhaseMetrics
from .loop import RunResult
from .metrics import json_safe
from .plots import write_compare, write_plot  # noqa: F401 - write_plot: used by the workers
from .summary import render_html, render_markdown, summary_blocks

SUMMARY_KEYS = (
    "tuning_duration_s",
    *kept_values.metric_of(kept_values.TUNED).values(),
    *kept_values.metric_of(kept_values.ADAPTER).values(),
    "dead_time_s",
    "rise_time_s",
    "settling_time_2pct_s",
    "settling_time_5pct_s",
    "overshoot_pct",
    "iae_c_s",
    "ise_c2_s",
    "itae_c_s2",
    "ss_peak_to_peak_c",
    "ss_std_c",
    "max_deviation_c",
    "recovery_time_2pct_s",
    "max_tracking_error_c",
    "tv_output_pct",
    "pwm_switches_per_min",
    "saturation_time_s",
)


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").lower() or "run"


def write_csv(result: RunResult, path: Path) -> None:
    gain_roles = sorted({r for tr in result.zones for r in tr.gains})
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(
            [
                "t_s",
                "zone",
                "phase",
                "pv_c",
                "true_c",
                "setpoint_c",
                "output_pct",
                "y_pct",
                "pwm",
                "state",
                "alarm",
                *gain_roles,
            ]
        )
        for tr in result.zones:
            for i, t in enumerate(tr.t):
                row = [
                    f"{t:.3f}",
                    tr.name,
                    tr.phase[i],
                    f"{tr.pv[i]:.4f}",
                    f"{tr.true_c[i]:.4f}",
                    f"{tr.setpoint[i]:.4f}",
                    f"{tr.u[i]:.4f}",
                    f"{tr.y[i]:.4f}" if tr.y else "",
                    tr.pwm[i] if tr.pwm else "",
                    tr.state[i],
                    f"0x{tr.alarm[i]:08X}" if tr.alarm else "",
                ]
                row += [f"{tr.gains[r][i]:.6g}" if r in tr.gains else "" for r in gain_roles]
                w.writerow(row)


def _fmt(v: object) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "–"
        return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"
    return str(v)


def summary_rows(runs: list[tuple[RunResult, list[PhaseMetrics]]]) -> tuple[list[str], list[list[str]]]:
    """Rows: (zone, phase, metric); columns: one per variant."""
    header = ["zone", "phase", "metric"] + [r.variant.name for r, _ in runs]
    keys: list[tuple[str, str, str]] = []
    for _, pms in runs:
        for pm in pms:
            for k in SUMMARY_KEYS:
                if k in pm.values and (pm.zone, pm.phase, k) not in keys:
                    keys.append((pm.zone, pm.phase, k))
    rows = []
    for zone, phase, k in keys:
        row = [zone, phase, k]
        for _, pms in runs:
            hit = next((pm for pm in pms if pm.zone == zone and pm.phase == phase), None)
            row.append(_fmt(hit.values.get(k)) if hit is not None else "–")
        rows.append(row)
    return header, rows


def text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))
    out = [line, "  ".join("-" * w for w in widths)]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(out)


def partial_reason(runs: list[tuple[RunResult, list[PhaseMetrics]]]) -> str | None:
    """Why the run is incomplete (the first variant's error), or None for a complete run."""
    return next((f"{r.variant.name}: {r.error}" for r, _ in runs if r.error), None)


def write_reports(
    runs: list[tuple[RunResult, list[PhaseMetrics]]], out_dir: Path, command: str | None = None
) -> dict[str, Path]:
    """Every report file. An interrupted run (SIGINT/SIGTERM: the user wants out now) gets no plots, only
    the CSV traces, metrics.json and the summaries, marked partial."""
    out_dir.mkdir(parents=True, exist_ok=True)
    draw = not any(r.interrupted for r, _ in runs)
    written: dict[str, Path] = {}
    scenario = runs[0][0].scenario
    partial = partial_reason(runs)
    doc = {
        "scenario": scenario.name,
        "file": str(scenario.path),
        "description": scenario.description,
        "reference": scenario.reference,
        "complete": not partial,
        "partial_reason": partial,
        "command": command,
        "variants": [],
    }
    plots: dict[str, str] = {}
    for result, pms in runs:
        tag = slug(result.variant.name)
        csv_path, png_path = out_dir / f"trace_{tag}.csv", out_dir / f"plot_{tag}.png"
        write_csv(result, csv_path)
        written[f"csv:{tag}"] = csv_path
        if draw and any(tr.t for tr in result.zones):
            if result.plot_path is None or Path(result.plot_path) != png_path or not png_path.exists():
                write_plot(result, png_path)
            written[f"png:{tag}"] = png_path
            plots[result.variant.name] = png_path.name
        doc["variants"].append(
            {
                "name": result.variant.name,
                "error": result.error,
                "run": json_safe(
                    {
                        "steps": float(result.steps),
                        "plant_time_s": result.plant_time_s,
                        "wall_s": result.wall_s,
                        "speedup_x": result.plant_time_s / result.wall_s if result.wall_s > 0 else math.nan,
                    }
                ),
                "phases": [
                    {
                        "zone": pm.zone,
                        "phase": pm.phase,
                        "kind": pm.kind,
                        "t_start_s": pm.t_start_s,
                        "t_end_s": pm.t_end_s,
                        "outcome": pm.outcome,
                        "info": pm.info,
                        "metrics": json_safe(pm.values),
                    }
                    for pm in pms
                ],
            }
        )
    from .verdict import verdict_rows

    doc["verdict"] = [vars(r) | {"verdict": r.verdict} for r in verdict_rows(runs)]
    metrics_path = out_dir / "metrics.json"
    metrics_path.write_text(json.dumps(doc, indent=2, default=str) + "\n", encoding="utf-8")
    written["metrics"] = metrics_path
    compare = out_dir / "compare.png"
    compare_png = (
        compare.name if draw and len(runs) > 1 and write_compare([r for r, _ in runs], compare) else None
    )
    if compare_png:
        written["png:compare"] = compare
    header, rows = summary_rows(runs)
    blocks = summary_blocks(runs, header, rows, partial=partial, compare_png=compare_png, command=command,
                            plots=plots)
    (out_dir / "summary.md").write_text(render_markdown(blocks), encoding="utf-8")
    written["summary_md"] = out_dir / "summary.md"
    (out_dir / "summary.html").write_text(render_html(blocks, scenario.name), encoding="utf-8")
    written["summary_html"] = out_dir / "summary.html"
    return written
