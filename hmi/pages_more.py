"""Fuzzy explain page (why the gains moved) and diagnostics (connection, latency, scans, faults, audit)."""

from __future__ import annotations

import json
import time

from nicegui import ui

from .fuzzy_tables import OUTPUTS, preset_names, preset_tables
from .layout import frame, panel, value_text
from .model import ZoneModel, fmt
from .pages_eng import _when, _zone_select
from .pages_live import TREND_COLUMNS, LiveFeed

SETS = ("NB", "NM", "NS", "ZO", "PS", "PM", "PB")
RULE_CODE_BASE = 10  # rule code = 10 * E set + EC set (register comment of nFuzzyRule<k>)
MS_TOLERANCE = 1e-3  # the PLC's bisection may leave the worst Ms this far above its bound
STATUS_GROUPS = ("status", "safety")  # shown on the diagnostics page, whatever registers they hold


@ui.page("/fuzzy")
def fuzzy_page(zone: int = 1) -> None:
    p = panel()
    frame("Fuzzy gain adapter: why the gains move")
    z = _zone_select(zone, "/fuzzy")
    with ui.row().classes("gap-8"):
        with ui.column():
            labels = {}
            for role, text in (("fuzzy", "adapter on"), ("fz_e", "e = W - X"), ("fz_ec", "ec"),
                               ("fz_eq", "E (quantised)"), ("fz_ecq", "EC (quantised)"), ("fz_dkp", "ΔKp"),
                               ("fz_dki", "ΔKi"), ("fz_dkd", "ΔKd"), ("fz_kp", "Kp effective"),
                               ("kp_base", "Kp base"), ("fz_tn", "Tn effective"), ("tn_base", "Tn base"),
                               ("fz_tv", "Tv effective"), ("tv_base", "Tv base")):
                if z.has(role):
                    with ui.row().classes("items-baseline"):
                        ui.label(text).classes("w-32 text-grey-8")
                        labels[role] = ui.label().classes("text-subtitle1").props(f'data-testid="fz-{role}"')
            explain = ui.label().classes("w-96 text-body2").props('data-testid="fz-explain"')
            robust = ui.label().classes("w-96 text-body2").props('data-testid="fz-robust"')
            symmetric = ui.label().classes("w-96 text-body2").props('data-testid="fz-symmetric"')
        with ui.column():
            if z.has("fuzzy"):
                sw = ui.switch("fuzzy adapter on (engineer)", value=bool(p.value(z["fuzzy"]))).props(
                    'data-testid="fz-switch"')
                sw.on_value_change(lambda e: _fuzzy_switch(z, sw, bool(e.value)))
            output = ui.toggle(list(OUTPUTS), value="Kp").props('data-testid="fz-output"')
            table_note = ui.label().classes("text-caption w-96").props('data-testid="fz-table-note"')
            heat = _heatmap()
    state = {"preset": None, "tables": None, "cells": None, "output": None}
    ui.label("Effective (solid) vs base gains over time").classes("text-subtitle1")
    chart = ui.echart({
        "animation": False, "legend": {}, "tooltip": {"trigger": "axis"},
        "xAxis": {"type": "time"}, "yAxis": [{"type": "value", "scale": True, "name": "Kp"},
                                             {"type": "value", "scale": True, "name": "s"}],
        "dataZoom": [{"type": "inside", "filterMode": "none"}],
        "series": [{"name": "Kp eff", "type": "line", "showSymbol": False, "data": []},
                   {"name": "Tn eff", "type": "line", "showSymbol": False, "yAxisIndex": 1, "data": []},
                   {"name": "Kp base", "type": "line", "showSymbol": False, "data": [],
                    "lineStyle": {"type": "dashed"}},
                   {"name": "Tn base", "type": "line", "showSymbol": False, "yAxisIndex": 1, "data": [],
                    "lineStyle": {"type": "dashed"}}],
    }).classes("w-full h-64")
    feed = LiveFeed(chart, z, 600.0, [TREND_COLUMNS.index("Kp"), TREND_COLUMNS.index("Tn"), 10, 11])
    base_cols = {"kp_base": 10, "tn_base": 11}
    # base gains are extra columns appended to each row (the shared trend rows stop at "alarm")
    feed.extra = [z[r] if z.has(r) else None for r in base_cols]

    def refresh() -> None:
        for role, lab in labels.items():
            lab.set_text(value_text(z[role]))
        cells = []
        for strength_tag, code_tag in z.rules:
            strength, code = p.value(strength_tag), p.value(code_tag)
            if strength is None or code is None or float(strength) <= 0:
                continue
            e_set, ec_set = divmod(int(code), RULE_CODE_BASE)
            if 0 <= e_set < len(SETS) and 0 <= ec_set < len(SETS):
                cells.append((ec_set, e_set, round(float(strength), 2)))
        preset = p.value(z["fz_preset"]) if z.has("fz_preset") else None
        if preset is not None and preset != state["preset"]:
            state["preset"], state["tables"] = preset, preset_tables(int(preset))
            name = preset_names().get(int(preset), str(preset))
            table_note.set_text(
                f"Rule table of preset {name} (nFuzzyPreset = {int(preset)}) as shipped in st_lib; colour = "
                "consequent NB (-3) .. PB (3), framed cells fire now (strength as label). A table changed "
                "through the rule mailbox cannot be read back over Modbus."
                if state["tables"] else f"preset {name}: rule table not readable from st_lib")
            state["cells"] = None
        if cells != state["cells"] or output.value != state["output"]:
            state["cells"], state["output"] = cells, output.value
            heat.run_chart_method("setOption", {"series": [{"data": _heat_data(state["tables"], output.value,
                                                                                cells)}]})
        if cells:
            top = max(cells, key=lambda c: c[2])
            explain.set_text(
                f"Strongest rule: IF E is {SETS[top[1]]} AND EC is {SETS[top[0]]} (strength {fmt(top[2])}) → "
                f"ΔKp {value_text(z['fz_dkp']) if z.has('fz_dkp') else '-'}, "
                f"ΔKi {value_text(z['fz_dki']) if z.has('fz_dki') else '-'}, "
                f"ΔKd {value_text(z['fz_dkd']) if z.has('fz_dkd') else '-'}: "
                f"Kp {value_text(z['kp_base']) if z.has('kp_base') else '-'} → "
                f"{value_text(z['fz_kp']) if z.has('fz_kp') else '-'}.")
        else:
            explain.set_text("No rule fires (adapter off or not running): the base gains are in use.")
        robust.set_text(_robustness_text(z))
        symmetric.set_text(_symmetric_text(z))
        _push_with_base(feed)

    ui.timer(0.2, refresh)


def _robustness_text(z: ZoneModel) -> str:
    """The adapter's Ms bound: worst Ms over every gain set it can reach vs the bound, and what keeping it
    cost (share of the ratio box kept, scale of the base gains)."""
    p = panel()
    if not z.has("fz_ms_reachable"):
        return ""
    reachable = p.value(z["fz_ms_reachable"])
    bound = p.value(z["fz_ms_max"]) if z.has("fz_ms_max") else None
    if reachable is None:
        return "Ms over reachable sets: not read yet"
    if not reachable:
        if bound is not None and bound <= 1.0:
            return "Ms over reachable sets not bounded: Ms bound off (fFuzzyMsMax <= 1); the configured " \
                   "ratio box is used."
        return ("Ms over reachable sets not bounded yet: no identified model or no valid base set (the "
                "configured ratio box is used), or the box is being searched (at most 15 control cycles, "
                "on the base gains).")
    text = f"Ms over reachable sets {value_text(z['fz_ms_reachable'], decimals=3)}"
    if bound is not None:
        holds = float(reachable) <= float(bound) * (1.0 + MS_TOLERANCE)
        text += f" {'≤' if holds else '>'} {value_text(z['fz_ms_max'])}"
    cost = []
    share = p.value(z["fz_box_share"]) if z.has("fz_box_share") else None
    if share is not None:
        cost.append(f"box {100.0 * float(share):.0f} %")
    if z.has("fz_gain_scale"):
        cost.append(f"gains × {value_text(z['fz_gain_scale'])}")
    return text + (f" ({', '.join(cost)})" if cost else "")


def _symmetric_text(z: ZoneModel) -> str:
    p = panel()
    if not z.has("fz_symmetric"):
        return ""
    on = p.value(z["fz_symmetric"])
    if on is None:
        return ""
    if not on:
        return "Rule table read as printed (symmetric use off): an approach from above differs from below."
    band = f", sign of e kept inside ±{value_text(z['fz_sign_band'])}" if z.has("fz_sign_band") else ""
    return f"Symmetric table use on (E and EC times the sign of e){band}."


async def _fuzzy_switch(z, sw: ui.switch, on: bool) -> None:
    from .auth import ENGINEER

    p = panel()
    if bool(p.value(z["fuzzy"])) == on:
        return
    result = await p.write({z["fuzzy"]: on}, ENGINEER, f"fuzzy adapter zone {z.number}")
    if result is None or not result.ok:
        sw.set_value(bool(p.value(z["fuzzy"])))


def _heatmap() -> ui.echart:
    return ui.echart({
        "animation": False, "tooltip": {},
        "grid": {"left": 60, "right": 20, "top": 30, "bottom": 60},
        "xAxis": {"type": "category", "data": list(SETS), "name": "EC"},
        "yAxis": {"type": "category", "data": list(SETS), "name": "E"},
        "visualMap": {"min": -3, "max": 3, "calculable": False, "orient": "horizontal", "left": "center",
                      "bottom": 0, "inRange": {"color": ["#1565c0", "#f5f5f5", "#d32f2f"]}},
        "series": [{"type": "heatmap", "data": [], "label": {"show": True}}],
    }).classes("w-96 h-96").props('data-testid="fz-heatmap"')


def _heat_data(tables: dict | None, output: str, cells: list[tuple[int, int, float]]) -> list:
    """One item per (EC, E) cell: the consequent as colour, the firing strength framed and labelled."""
    firing = {(x, y): v for x, y, v in cells}
    data = []
    for y in range(len(SETS)):
        for x in range(len(SETS)):
            value = tables[output][y][x] if tables else 0
            item: dict = {"value": [x, y, value]}
            if (x, y) in firing:
                item["itemStyle"] = {"borderColor": "#000", "borderWidth": 3}
                item["label"] = {"formatter": f"{value} @{firing[(x, y)]:.2f}", "fontWeight": "bold"}
            data.append(item)
    return data


def _push_with_base(feed: LiveFeed) -> None:
    """Like LiveFeed.push, with the base gains (slow registers, current value) appended to each row."""
    from .pages_live import _row

    p = panel()
    samples = p.poller.samples
    if not samples or samples[-1].seq <= feed.last_seq:
        return
    extra = [p.value(n) if n else None for n in feed.extra]
    rows = [_row(s.t, s.values, feed.z) + extra for s in samples if s.seq > feed.last_seq]
    feed.last_seq = samples[-1].seq
    ui.run_javascript(f"thermost.add({feed.chart.id}, {json.dumps(rows)})")


@ui.page("/diag")
def diag_page() -> None:
    p = panel()
    frame("Diagnostics")
    info = ui.label().classes("text-body1").props('data-testid="diag-info"')
    zones = ui.label().classes("text-body2").props('data-testid="diag-zones"')
    status_names = [n for n, m in p.model.meta.items()
                    if m.owner == "plc" and (m.group in STATUS_GROUPS or m.zone is None)]
    ui.label("Status and safety registers (owner plc)").classes("text-h6")
    status = ui.table(columns=[{"name": c, "label": c, "field": c, "align": "left"}
                               for c in ("tag", "value", "description")],
                      rows=[], row_key="tag").classes("w-full").props('data-testid="diag-status"')
    ui.label("Audit log (every write from the panel)").classes("text-h6")
    audit = ui.table(columns=[{"name": c, "label": c, "field": c, "align": "left"}
                              for c in ("time", "level", "tag", "old", "new", "result", "message")],
                     rows=[], row_key="key", pagination=15).classes("w-full").props('data-testid="audit"')

    def refresh() -> None:
        d = p.poller.diag
        med, p95 = p.poller.latency_stats()
        age = time.time() - d.last_ok if d.last_ok else float("inf")
        info.set_text(
            f"PLC {p.plc_label}: {'connected' if d.connected else 'NOT connected'}"
            f"{'' if d.connected else ' (' + d.error + ')'}; last good read {age:.1f} s ago; "
            f"poll {p.poller.rate_hz:g} Hz, {d.requests_per_cycle} Modbus requests per cycle, "
            f"latency median {fmt(med, 2)} ms, p95 {fmt(p95, 2)} ms; cycles {d.cycles}, "
            f"failures {d.failures}, "
            f"reconnects {d.reconnects}; scan counter "
            + (f"{d.scan_count} ({fmt(d.scan_rate_hz, 1)} scans/s)" if d.scan_count is not None
               else "not offered by this PLC"))
        parts = []
        for z in p.model.zones:
            err = int(p.value(z["error"]) or 0) if z.has("error") else 0
            parts.append(f"zone {z.number}: error id {err} ({p.poller.error_text.get(err, '?')}), alarm word "
                         f"{int(p.value(z['alarm']) or 0):#010x}")
        zones.set_text("; ".join(parts))
        srows = [{"tag": n, "value": value_text(n), "description": p.model.regmap[n].comment}
                 for n in status_names]
        if srows != status.rows:
            status.rows = srows
        rows = [{"key": i, "time": _when(t), "level": lv, "tag": tag, "old": old, "new": new, "result": res,
                 "message": msg} for i, (t, lv, tag, old, new, res, msg) in enumerate(p.store.audit(200))]
        if rows != audit.rows:
            audit.rows = rows

    refresh()
    ui.timer(1.0, refresh)
