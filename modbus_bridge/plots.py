"""Plots of a run (matplotlib, Agg): one per variant, and the variants overlaid on one axis.

Both mark what happened: phase starts with the mode they set (grey), disturbances (red, dashed, named),
alarms (red shading where the alarm word is not 0), and the 2 % settling band around the setpoint after a
setpoint step. Gains each on their own axis with their unit: Kp in %/°C, Tn and Tv in s.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .loop import RunResult, ZoneTrace

SETTLING_BAND = 0.02
GAIN_AXES = (  # (roles, axis label)
    (("kp", "kp_eff"), "Kp (%/°C)"),
    (("tn", "tn_eff", "tv", "tv_eff"), "Tn, Tv (s)"),
)
GAIN_LABELS = {"kp": "Kp", "kp_eff": "Kp in use", "tn": "Tn", "tn_eff": "Tn in use",
               "tv": "Tv", "tv_eff": "Tv in use"}
COOLING_ROLES = {"kp": "kp_cool", "tn": "tn_cool", "tv": "tv_cool"}


def gain_lines(tr: ZoneTrace) -> list[list[tuple[str, str]]]:
    """Per gain axis, the (role, label) pairs to draw. A zone whose output went below 0 % ran on its cooling
    set there, which the fuzzy adapter rewrites as well: that set is drawn too and the tuned ones are marked
    heating or cooling; the set in use is whichever of them the PID ran on at the time."""
    cools = bool(tr.u) and min(tr.u) < 0.0
    axes = []
    for roles, _ in GAIN_AXES:
        lines = []
        for role in roles:
            if role in tr.gains:
                side = ", heating" if cools and role in COOLING_ROLES else ""
                lines.append((role, GAIN_LABELS[role] + side))
            cool = COOLING_ROLES.get(role)
            if cools and cool in tr.gains:
                lines.append((cool, f"{GAIN_LABELS[role]}, cooling"))
        axes.append(lines)
    return axes


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def settling_bands(tr: ZoneTrace) -> list[tuple[float, float, float, float]]:
    """(t_start, t_end, low, high) of the 2 % band after every setpoint step."""
    bands = []
    for rec in tr.phases:
        before, after = rec.setpoint_before, rec.setpoint
        if math.isfinite(before) and math.isfinite(after) and before != after and rec.ramp_c_per_min is None:
            half = SETTLING_BAND * abs(after - before)
            bands.append((rec.t_start, rec.t_end, after - half, after + half))
    return bands


def mark_events(ax, tr: ZoneTrace, *, labels: bool = True, bands: bool = True) -> None:
    """Phase starts (with the mode), disturbances, alarm spans and (bands) settling bands on one axis."""
    for rec in tr.phases:
        ax.axvline(rec.t_start, color="grey", lw=0.5)
        if labels:
            text = rec.name + (f" ({rec.mode})" if rec.mode else "")
            ax.annotate(text, (rec.t_start, 0.98), xycoords=("data", "axes fraction"), xytext=(2, 0),
                        textcoords="offset points", fontsize=7, va="top", ha="left", rotation=90,
                        color="dimgrey")
        for t, kind, value in rec.disturbances:
            ax.axvline(t, color="tab:red", lw=0.8, ls="--")
            if labels:
                ax.annotate(f"{kind} {value if value is not None else ''}".strip(), (t, 0.45),
                            xycoords=("data", "axes fraction"), xytext=(2, 0), textcoords="offset points",
                            fontsize=7, rotation=90, color="tab:red")
    if bands:
        for k, (t0, t1, low, high) in enumerate(settling_bands(tr)):
            ax.fill_between([t0, t1], low, high, color="tab:green", alpha=0.2, lw=0,
                            label="±2 % settling band" if k == 0 and labels else None)
    if tr.alarm:
        t, words = np.asarray(tr.t), np.asarray(tr.alarm)
        active = words != 0
        if active.any():
            seen = ", ".join(f"16#{w:08X}" for w in sorted(set(words[active].tolist()))[:3])
            ax.fill_between(t, 0, 1, where=active, transform=ax.get_xaxis_transform(), color="tab:red",
                            alpha=0.10, lw=0, label=f"alarm word {seen}" if labels else None)


def _temperature_limits(ax, traces: list[ZoneTrace]) -> None:
    """Zoom on the process: an open sensor's 1000 °C reading must not flatten everything else."""
    values = np.concatenate([np.asarray(tr.true_c) for tr in traces] +
                            [np.asarray(tr.setpoint)[np.isfinite(tr.setpoint)] for tr in traces])
    if values.size:
        low, high = float(np.min(values)), float(np.max(values))
        pad = max(1.0, 0.08 * (high - low))
        ax.set_ylim(low - pad, high + pad)


def write_plot(result: RunResult, path: Path) -> None:
    """One variant: temperature, output, Kp, Tn/Tv per zone (columns)."""
    plt = pyplot()
    n = len(result.zones)
    fig, axes = plt.subplots(4, n, figsize=(8 * n, 10), sharex="col", squeeze=False,
                             gridspec_kw={"height_ratios": [3, 1.5, 1, 1]})
    for j, tr in enumerate(result.zones):
        ax_t, ax_u, ax_kp, ax_tn = (axes[i][j] for i in range(4))
        ax_t.plot(tr.t, tr.pv, label="PV (measured)", lw=1)
        ax_t.plot(tr.t, tr.true_c, label="true temperature", lw=0.6, alpha=0.7)
        ax_t.plot(tr.t, tr.setpoint, label="setpoint", lw=1, ls="--", color="black")
        mark_events(ax_t, tr)
        _temperature_limits(ax_t, [tr])
        ax_t.set_ylabel("temperature (°C)")
        ax_t.set_title(f"{result.scenario.name} – {tr.name} – {result.variant.name}", fontsize=10)
        ax_t.legend(fontsize=7, loc="lower right")
        ax_u.plot(tr.t, tr.u, lw=0.8, color="tab:red")
        mark_events(ax_u, tr, labels=False, bands=False)
        ax_u.set_ylabel("output (%)")
        for ax, (_, label), lines in zip((ax_kp, ax_tn), GAIN_AXES, gain_lines(tr), strict=True):
            for role, line_label in lines:
                ax.plot(tr.t, tr.gains[role], lw=0.9, label=line_label)
            ax.set_ylabel(label)
            if ax.lines:
                ax.legend(fontsize=7, loc="upper right")
        ax_tn.set_xlabel("plant time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_compare(results: list[RunResult], path: Path) -> bool:
    """Every variant on one axis per zone: temperature (with setpoint, settling band, events) and output.
    False when there is nothing to draw."""
    drawn = [r for r in results if any(tr.t for tr in r.zones)]
    if not drawn:
        return False
    plt = pyplot()
    names = [tr.name for tr in drawn[0].zones]
    fig, axes = plt.subplots(2, len(names), figsize=(10 * len(names), 7), sharex="col", squeeze=False,
                             gridspec_kw={"height_ratios": [3, 1.3]})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, name in enumerate(names):
        ax_t, ax_u = axes[0][j], axes[1][j]
        traces = []
        for k, result in enumerate(drawn):
            tr = next((z for z in result.zones if z.name == name), None)
            if tr is None or not tr.t:
                continue
            traces.append(tr)
            color = colors[k % len(colors)]
            ax_t.plot(tr.t, tr.pv, lw=1, color=color, label=result.variant.name)
            ax_u.plot(tr.t, tr.u, lw=0.8, color=color, label=result.variant.name)
        first = traces[0]
        ax_t.plot(first.t, first.setpoint, lw=1, ls="--", color="black", label="setpoint")
        mark_events(ax_t, first)
        mark_events(ax_u, first, labels=False, bands=False)
        _temperature_limits(ax_t, traces)
        ax_t.set_ylabel("PV (°C)")
        ax_t.set_title(f"{drawn[0].scenario.name} – {name}: variants compared", fontsize=10)
        ax_t.legend(fontsize=8, loc="lower right")
        ax_u.set_ylabel("output (%)")
        ax_u.set_xlabel("plant time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True
