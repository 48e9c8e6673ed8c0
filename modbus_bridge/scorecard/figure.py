"""The scorecard's PNG of one scenario: every row's trace over the scored window, overlaid.

Panels: the true temperature (what the columns judge) with the bounds and the 2 % band; the same near its
target, as the deviation from the setpoint, where overshoot and settling are decided; the controller's
output; and, when a row adapts its gains (the fuzzy PID), its Kp and Ki over the base set it started from,
which shows why it lands where it does."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..metrics import BAND_2PCT
from ..plots import pyplot
from .build import Card, Row, window

ZOOM_BANDS = 6.0  # the near-the-target panel spans this many bands either side of the setpoint
ADAPTING = 0.01  # a row whose gain ratios leave 1 by more than this share is drawn in the gain panel


@dataclass
class GainRatios:
    t: np.ndarray
    kp: np.ndarray
    ki: np.ndarray | None  # None: the base set has no I part


def gain_ratios(r: Row, phase: str | None) -> GainRatios | None:
    """Kp and Ki in use over the row's base set through the window, for a row that adapts its gains; None
    unless they moved. Where the output is on the other side of a split range the PID runs the other set
    (a cooling-tuned zone heating): those samples are left out (NaN)."""
    o, base = r.outcome, r.gains
    if not r.adapts or o is None or base is None or base.kp <= 0.0 or "kp_eff" not in o.gains:
        return None
    m, start = window(o, phase)
    out = (o.y if o.y is not None else o.u)[m]
    other_side = out > 0.0 if r.cooling else out < 0.0
    kp = np.where(other_side, np.nan, o.gains["kp_eff"][m])
    ki = None
    if base.tn > 0.0 and "tn_eff" in o.gains:
        tn = o.gains["tn_eff"][m]
        with np.errstate(divide="ignore", invalid="ignore"):
            ki = np.where(tn > 0.0, kp / tn, np.nan) / (base.kp / base.tn)
    ratios = GainRatios(o.t[m] - start, kp / base.kp, ki)
    moved = [float(np.nanmax(np.abs(x - 1.0))) for x in (ratios.kp, ratios.ki)
             if x is not None and np.isfinite(x).any()]
    return ratios if moved and max(moved) > ADAPTING else None


def write_png(card: Card, path: Path) -> None:
    plt = pyplot()
    adapting = [(r, g) for r in card.rows if (g := gain_ratios(r, card.scored_phase)) is not None]
    heights = (2.0, 1.3, 1.0, 1.0) if adapting else (2.0, 1.3, 1.0)
    fig, axes = plt.subplots(len(heights), 1, figsize=(9, 2.2 * sum(heights)), sharex=True,
                             height_ratios=heights)
    ax, axz, axu = axes[:3]
    colours = {}
    end, band = 0.0, None
    if card.step is not None:
        band = BAND_2PCT * abs(card.step[1] - card.step[0])
    for r in card.rows:
        if r.outcome is None:
            continue
        t, true_c, w, u = _traces(r, card.scored_phase)
        (line,) = ax.plot(t, true_c, lw=1.1, label=r.name)
        colours[r.name] = c = line.get_color()
        axz.plot(t, true_c - w, lw=1.0, color=c)
        axu.plot(t, u, lw=0.9, color=c)
        end = max(end, float(t[-1]) if t.size else 0.0)
    bounds = ((card.bound, "--", "bound (bang-hold)"), (card.braked, ":", "bound with a brake"))
    for bound, style, label in bounds:
        if bound is not None:
            ax.plot(bound.t, bound.y, "k" + style, lw=1.2, label=label)
            axz.plot(bound.t, bound.y - card.step[1], "k" + style, lw=1.0)
            axu.plot(bound.t, bound.inputs(), "k" + style, lw=1.0)
    if band is not None:
        r0 = card.step[1]
        ax.axhspan(r0 - band, r0 + band, color="0.85", zorder=0, label="±2 % band")
        axz.axhspan(-band, band, color="0.85", zorder=0)
        axz.set_ylim(-ZOOM_BANDS * band, ZOOM_BANDS * band)
    ax.set_xlim(0.0, end if end > 0 else None)
    ax.set_ylabel("true temperature (°C)")
    what = (f"from the step (phase '{card.scored_phase}')" if card.step
            else f"from the first load or ramp (phase '{card.scored_phase}')")
    ax.set_title(f"{card.scenario.name}: zone 1 {what}", fontsize=10)
    ax.legend(fontsize=7, loc="best")
    axz.set_ylabel("true − setpoint (°C)", fontsize=9)
    axz.axhline(0.0, color="k", lw=0.6)
    axu.set_ylabel("controller output (%)", fontsize=9)
    if adapting:
        axg = axes[3]
        for r, g in adapting:
            c = colours.get(r.name)
            axg.plot(g.t, g.kp, lw=1.0, color=c, label=f"{r.name}: Kp / base Kp")
            if g.ki is not None:
                axg.plot(g.t, g.ki, lw=1.0, ls=":", color=c, label=f"{r.name}: Ki / base Ki")
        axg.axhline(1.0, color="k", lw=0.6)
        axg.set_ylabel("gain / base set", fontsize=9)
        axg.legend(fontsize=7, loc="best")
    for a in axes:
        a.grid(alpha=0.3)
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _traces(r: Row, phase: str | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """t from the start of `phase` (or of the scored window), the true temperature, the setpoint and the
    controller's output (its register: a PWM heater's duty switches 0/100 every period and would hide it)."""
    o = r.outcome
    assert o is not None
    m, start = window(o, phase)
    out = o.y if o.y is not None else o.u
    return o.t[m] - start, o.true_c[m], o.setpoint[m], out[m]
