"""Live pages: overview (one card per zone), zone faceplate, trend."""

from __future__ import annotations

import json
import time

from nicegui import ui

from .auth import ENGINEER, OPERATOR
from .layout import frame, live_text, number_or_error, panel, value_text
from .model import MODE_BUTTONS, ZoneModel, fmt

SPARK_S = 120.0
TREND_KEEP_S = 600.0
TREND_COLUMNS = ("t", "PV", "W", "output", "Kp", "Tn", "Tv", "Td", "state", "alarm")
TREND_ROLES = (("pv",), ("setpoint",), ("y",), ("kp_eff", "kp"), ("tn_eff", "tn"), ("tv_eff", "tv"),
               ("td_eff", "td"), ("state",), ("alarm",))
HISTORY_PRELOAD_S = 600.0


def _zone_name(z: ZoneModel) -> str:
    return f"Zone {z.number}"


def _role(z: ZoneModel, roles: tuple[str, ...]) -> str | None:
    return next((z[r] for r in roles if z.has(r)), None)


def _row(t: float, values: dict, z: ZoneModel) -> list:
    out: list = [round(t * 1000)]
    for roles in TREND_ROLES:
        name = _role(z, roles)
        v = values.get(name) if name else None
        out.append(None if v is None else (round(float(v), 4) if isinstance(v, float) else int(v)))
    return out


class LiveFeed:
    """Sends a chart the samples it has not seen (by sequence number), at the page's pace."""

    def __init__(self, chart: ui.echart, z: ZoneModel, keep_s: float, series: list[int], state: int = -1,
                 alarm: int = -1) -> None:
        self.chart, self.z = chart, z
        self.last_seq = 0
        self.sent = 0
        self.extra: list = []  # tag names whose current value is appended to each row
        cfg = {"columns": list(TREND_COLUMNS), "series": series, "state": state, "alarm": alarm,
               "keep_s": keep_s}
        ui.run_javascript(f"thermost.setup({chart.id}, {json.dumps(cfg)})")

    def preload(self, rows: list[list]) -> None:
        if rows:
            ui.run_javascript(f"thermost.add({self.chart.id}, {json.dumps(rows)}, true)")

    def push(self) -> None:
        samples = panel().poller.samples
        if not samples or samples[-1].seq <= self.last_seq:
            return
        rows = [_row(s.t, s.values, self.z) for s in samples if s.seq > self.last_seq]
        backlog = "true" if self.last_seq == 0 else "false"  # the ring buffer on first contact: history
        self.last_seq = samples[-1].seq
        self.sent += len(rows)
        # json.dumps writes NaN / Infinity, which are valid JavaScript expressions
        self.chart.client.run_javascript(f"thermost.add({self.chart.id}, {json.dumps(rows)}, {backlog})")

    def follow(self) -> None:
        """Push each sample as soon as the poller has it (no page-timer wait), until the page goes."""
        listeners = panel().poller.listeners
        listeners.add(self.push)
        self.chart.client.on_delete(lambda: listeners.discard(self.push))


def _time_axis() -> dict:
    return {"type": "time", "axisLabel": {"hideOverlap": True}}


@ui.page("/")
def overview() -> None:
    p = panel()
    frame("Overview")
    with ui.row().classes("w-full gap-4"):
        for z in p.model.zones:
            _zone_card(z)


def _zone_card(z: ZoneModel) -> None:
    p = panel()
    with ui.card().classes("w-80 cursor-pointer").props(f'data-testid="card-{z.number}"').on(
            "click", lambda _e, n=z.number: ui.navigate.to(f"/zone/{n}")):
        ui.label(_zone_name(z)).classes("text-h6")
        pv = ui.label().classes("text-h4").props(f'data-testid="pv-{z.number}"')
        w = ui.label()
        state = ui.label().props(f'data-testid="state-{z.number}"')
        bar = ui.linear_progress(value=0, show_value=False).props("size=12px")
        ylab = ui.label()
        alarm = ui.label().classes("text-negative").props(f'data-testid="alarm-{z.number}"')
        spark = ui.echart({
            "animation": False, "grid": {"left": 30, "right": 4, "top": 4, "bottom": 16},
            "xAxis": {"type": "time", "show": False}, "yAxis": {"type": "value", "scale": True},
            "series": [{"type": "line", "showSymbol": False, "data": []}],
        }).classes("w-full h-20")
    feed = LiveFeed(spark, z, SPARK_S, [1])

    def refresh() -> None:
        live_text(pv, lambda: value_text(z["pv"], 1))
        live_text(w, lambda: "W " + value_text(z["setpoint"], 1))
        live_text(state, lambda: "state " + p.model.codes.state_name(int(p.value(z["state"]) or 0))
                  if p.value(z["state"]) is not None else "state -")
        y = p.value(z["y"])
        bar.set_value(0 if y is None else max(0.0, min(1.0, abs(float(y)) / 100.0)))
        live_text(ylab, lambda: "output " + value_text(z["y"], 1))
        active = [t.split(":")[0] for zn, _b, t in p.poller.active_alarms() if zn == z.number]
        alarm.set_text("; ".join(active) if active else "")
        feed.push()

    ui.timer(0.2, refresh)


@ui.page("/zone/{number}")
def zone_page(number: str) -> None:
    p = panel()
    zones = {str(z.number): z for z in p.model.zones}
    if number not in zones:
        frame("Zone")
        ui.label(f"no zone {number} (zones: {', '.join(zones)})").classes("text-negative")
        return
    z = zones[number]
    frame(f"{_zone_name(z)} faceplate")
    with ui.row().classes("gap-8"):
        with ui.column():
            labels = {}
            for role, text in (("pv", "PV"), ("setpoint", "W"), ("w_work", "W used"), ("y", "output"),
                               ("mode", "mode"), ("state", "state"), ("error", "error id")):
                with ui.row().classes("items-baseline"):
                    ui.label(text).classes("w-20 text-grey-8")
                    labels[role] = ui.label().classes("text-h6").props(f'data-testid="fp-{role}"')
            heatup = ui.label().props('data-testid="fp-heatup"')
        with ui.column():
            ui.label("Mode").classes("text-subtitle1")
            with ui.row():
                buttons = {}
                for mode in MODE_BUTTONS:
                    if mode in p.model.codes.modes:
                        buttons[mode] = ui.button(mode, on_click=lambda _e, m=mode: set_mode(m)).props(
                            f'data-testid="mode-{mode}"')
            _entry(z, "setpoint", "setpoint", "w_min", "w_max")
            _entry(z, "manual", "manual output", "y_min", "y_max")
            if z.has("setpoint2"):
                _entry(z, "setpoint2", "standby setpoint", "w_min", "w_max")
            for role, text in (("sel_setpoint", "standby setpoint active"), ("ramp", "setpoint ramp on"),
                               ("heat_up", "model-based heat-up on")):
                if z.has(role):
                    sw = ui.switch(text, value=bool(p.value(z[role]))).props(f'data-testid="sw-{role}"')
                    sw.on_value_change(lambda e, r=role, s=sw: _switch(z, r, s, e.value))

    async def set_mode(mode: str) -> None:
        needed = ENGINEER if mode == "TUNE" else OPERATOR  # tuning is the engineer's
        await p.write({z["mode"]: p.model.codes.modes[mode]}, needed, f"mode {mode}")

    def refresh() -> None:
        for role, lab in labels.items():
            if not z.has(role):
                lab.set_text("-")
            elif role == "state" and p.value(z["state"]) is not None:
                live_text(lab, lambda: p.model.codes.state_name(int(p.value(z["state"]))))
            elif role == "mode" and p.value(z["mode"]) is not None:
                code = int(p.value(z["mode"]))
                names = {v: k for k, v in p.model.codes.modes.items()}
                live_text(lab, lambda c=code, n=names: n.get(c, str(c)))
            else:
                live_text(lab, lambda r=role: value_text(z[r], 2))
        heatup.set_text(heatup_text(z))
        current = p.value(z["mode"])
        for mode, b in buttons.items():
            on = current is not None and p.model.codes.modes[mode] == int(current)
            b.props(f"color={'primary' if on else 'grey-6'}")

    ui.timer(0.2, refresh)


def heatup_text(z: ZoneModel) -> str:
    """The model-based setpoint response: its phase, and the plant its last limit phase saw beside the
    identified model ("" when the zone has no such response or none ever ran)."""
    p = panel()
    if not (z.has("heatup_state") and z.has("heatup_tu") and z.has("heatup_tg")):
        return ""
    state = p.value(z["heatup_state"])
    seen_tu, seen_tg = p.value(z["heatup_tu"]), p.value(z["heatup_tg"])
    if state is None or seen_tu is None or seen_tg is None:
        return ""
    text = f"heat-up {value_text(z['heatup_state'])}"
    if seen_tg > 0.0:
        text += f"; plant seen: L {value_text(z['heatup_tu'])}, T {value_text(z['heatup_tg'])}"
        if z.has("tu") and z.has("tg"):
            text += f" (model L {value_text(z['tu'])}, T {value_text(z['tg'])})"
    return text


async def _switch(z: ZoneModel, role: str, sw: ui.switch, value: bool) -> None:
    p = panel()
    if bool(p.value(z[role])) == bool(value):
        return
    result = await p.write({z[role]: bool(value)}, OPERATOR, role.replace("_", " "))
    if result is None or not result.ok:
        sw.set_value(bool(p.value(z[role])))


def _limit(z: ZoneModel, role: str | None, meta_bound: float | None) -> float | None:
    """The tighter of the tag's metadata bound and the live limit register the PLC enforces."""
    p = panel()
    live = p.value(z[role]) if role and z.has(role) else None
    return float(live) if isinstance(live, float) else meta_bound


def _entry(z: ZoneModel, role: str, text: str, lo_role: str, hi_role: str) -> None:
    p = panel()
    if not z.has(role):
        return
    name = z[role]
    meta = p.model.meta[name]
    with ui.row().classes("items-center"):
        box = ui.input(text).props(f'data-testid="in-{role}"').classes("w-40")
        hint = ui.label().classes("text-caption text-grey-7")
        msg = ui.label().classes("text-negative").props(f'data-testid="msg-{role}"')

        async def send() -> None:
            value, why = number_or_error(box.value)
            lo, hi = _limit(z, lo_role, meta.min), _limit(z, hi_role, meta.max)
            if why is None and lo is not None and value < lo:
                why = f"below {fmt(lo)} {meta.unit}".strip()
            if why is None and hi is not None and value > hi:
                why = f"above {fmt(hi)} {meta.unit}".strip()
            if why is None:
                why = meta.check(value)
            if why:
                msg.set_text(f"{text}: {why}; nothing written")
                return
            msg.set_text("")
            result = await p.write({name: value}, OPERATOR, text)
            if result is not None and not result.ok:
                msg.set_text(result.message)

        ui.button("Set", on_click=send).props(f'data-testid="set-{role}"')

    def hint_text() -> None:
        lo, hi = _limit(z, lo_role, meta.min), _limit(z, hi_role, meta.max)
        hint.set_text(f"{fmt(lo)} … {fmt(hi)} {meta.unit}".strip())

    hint_text()
    ui.timer(1.0, hint_text)


@ui.page("/trend")
def trend_page(zone: int = 1) -> None:
    p = panel()
    frame("Live trend")
    zones = {z.number: z for z in p.model.zones}
    z = zones.get(zone, p.model.zones[0])
    with ui.row().classes("items-center"):
        ui.select({n: f"Zone {n}" for n in zones}, value=z.number,
                  on_change=lambda e: ui.navigate.to(f"/trend?zone={e.value}"))
        pause = ui.switch("pause").props('data-testid="trend-pause"')
        ui.button("CSV of the visible window", on_click=lambda: ui.run_javascript(
            f"thermost.csv({chart.id}, 'thermost_zone{z.number}_trend.csv')")).props(
                'data-testid="trend-csv"')
        counter = ui.label().props('data-testid="trend-count"')
    unit_pv = p.model.meta[z["pv"]].unit or "degC"
    chart = ui.echart({
        "animation": False,
        "legend": {"top": 0},
        "tooltip": {"trigger": "axis"},
        "axisPointer": {"link": [{"xAxisIndex": "all"}]},
        "grid": [{"left": 60, "right": 60, "top": 30, "height": "50%"},
                 {"left": 60, "right": 60, "top": "68%", "height": "20%"}],
        "xAxis": [_time_axis() | {"gridIndex": 0}, _time_axis() | {"gridIndex": 1}],
        "yAxis": [{"type": "value", "scale": True, "name": unit_pv, "gridIndex": 0},
                  {"type": "value", "name": "%", "min": -100, "max": 100, "gridIndex": 0},
                  {"type": "value", "scale": True, "name": "Kp %/degC", "gridIndex": 1},
                  {"type": "value", "scale": True, "name": "s", "gridIndex": 1}],
        "dataZoom": [{"type": "inside", "xAxisIndex": [0, 1], "filterMode": "none"},
                     {"type": "slider", "xAxisIndex": [0, 1], "filterMode": "none", "bottom": 0}],
        "series": [
            {"name": "PV", "type": "line", "showSymbol": False, "data": []},
            {"name": "W", "type": "line", "showSymbol": False, "data": [], "lineStyle": {"type": "dashed"}},
            {"name": "output %", "type": "line", "showSymbol": False, "yAxisIndex": 1, "data": []},
            {"name": "Kp", "type": "line", "showSymbol": False, "xAxisIndex": 1, "yAxisIndex": 2, "data": []},
            {"name": "Tn s", "type": "line", "showSymbol": False, "xAxisIndex": 1, "yAxisIndex": 3,
             "data": []},
            {"name": "Tv s", "type": "line", "showSymbol": False, "xAxisIndex": 1, "yAxisIndex": 3,
             "data": []},
            {"name": "Td s", "type": "line", "showSymbol": False, "xAxisIndex": 1, "yAxisIndex": 3,
             "data": []},
        ],
    }).classes("w-full").style("height: 560px").props('data-testid="trend-chart"')
    feed = LiveFeed(chart, z, TREND_KEEP_S, [1, 2, 3, 4, 5, 6, 7], state=8, alarm=9)
    # history from the database first (survives a restart), then the live ring buffer
    first_live = p.poller.samples[0].t if p.poller.samples else time.time()
    rows = [[round(t * 1000), pv, w, y, kp, tn, tv, None, state, alarm]
            for t, pv, w, y, state, alarm, kp, tn, tv in
            p.store.samples(z.number, time.time() - HISTORY_PRELOAD_S, first_live)]
    feed.preload(rows)
    pause.on_value_change(
        lambda e: ui.run_javascript(f"thermost.pause({chart.id}, {json.dumps(bool(e.value))})"))

    feed.push()  # the ring buffer so far, then every new sample as it is read
    feed.follow()
    ui.timer(0.5, lambda: counter.set_text(f"{feed.sent} live samples"))
