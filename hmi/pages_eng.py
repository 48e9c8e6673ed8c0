"""Alarms (active + history, acknowledge), parameters (grouped, limits, refusals), tuning."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from nicegui import ui
from nicegui.events import ValueChangeEventArguments

from .auth import ENGINEER, OPERATOR
from .layout import frame, number_or_error, panel, value_text
from .model import GAIN_SET_ROLES, ZoneModel, fmt

GROUP_TITLES = {
    "pid_heating": "PID heating", "pid_cooling": "PID cooling", "limits": "Output limits and reaction",
    "pwm": "PWM", "setpoint": "Setpoint", "alarms": "Alarms", "tuning": "Tuning", "fuzzy": "Fuzzy adapter",
    "sensor": "Sensor", "safety": "Safety", "cycle": "Cycle times", "mode": "Mode", "process": "Process",
}
GROUP_ORDER = tuple(GROUP_TITLES)


def _when(t: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t)) + f".{int(t % 1 * 10)}"


def _zone_select(current: int, path: str) -> ZoneModel:
    p = panel()
    zones = {z.number: z for z in p.model.zones}
    ui.select({n: f"Zone {n}" for n in zones}, value=current if current in zones else 1,
              on_change=lambda e: ui.navigate.to(f"{path}?zone={e.value}")).props('data-testid="zone-select"')
    return zones.get(current, p.model.zones[0])


@ui.page("/alarms")
def alarms_page() -> None:
    p = panel()
    frame("Alarms")
    ui.label("Active").classes("text-h6")
    active = ui.table(columns=[{"name": "zone", "label": "zone", "field": "zone"},
                               {"name": "bit", "label": "bit", "field": "bit"},
                               {"name": "text", "label": "alarm", "field": "text", "align": "left"}],
                      rows=[], row_key="key").classes("w-full").props('data-testid="alarms-active"')
    with ui.row():
        for z in p.model.zones:
            if z.has("ack"):
                ui.button(f"Acknowledge zone {z.number}", on_click=lambda _e, zz=z: ack(zz)).props(
                    f'data-testid="ack-{z.number}"')
    ui.label("History").classes("text-h6")
    history = ui.table(columns=[{"name": c, "label": c, "field": c, "align": "left"}
                                for c in ("time", "zone", "bit", "event", "text", "level")],
                       rows=[], row_key="key", pagination=15).classes("w-full").props(
                           'data-testid="alarms-history"')

    async def ack(z: ZoneModel) -> None:
        before = p.poller.alarm_word(z.number)
        result = await p.write({z["ack"]: True}, OPERATOR, f"acknowledge zone {z.number}")
        if result is not None and result.ok:
            p.store.add_alarm_event(z.number, -1, "acknowledged", f"alarm word {before:#x} before",
                                    p.level())

    def refresh() -> None:
        rows = [{"key": f"{zn}.{b}", "zone": zn, "bit": b, "text": t}
                for zn, b, t in p.poller.active_alarms()]
        if rows != active.rows:
            active.rows = rows
        hist = [{"key": i, "time": _when(t), "zone": zn, "bit": "" if b < 0 else b, "event": ev, "text": tx,
                 "level": lv} for i, (t, zn, b, ev, tx, lv) in enumerate(p.store.alarm_events(300))]
        if hist != history.rows:
            history.rows = hist

    refresh()
    ui.timer(0.5, refresh)


@ui.page("/params")
def params_page(zone: int = 1) -> None:
    p = panel()
    frame("Parameters")
    z = _zone_select(zone, "/params")
    ui.label("Writable by the engineer level. The page refuses entries outside the range; the PLC checks "
             "them again and a value it does not take is shown with its reason.").classes("text-caption")
    groups = p.model.parameter_groups(z.number)
    order = [g for g in GROUP_ORDER if g in groups] + sorted(g for g in groups if g not in GROUP_ORDER)
    rows: list[tuple[str, ui.label]] = []
    switches: list[tuple[str, ui.switch]] = []
    writing: set[str] = set()  # coils whose write is in flight: their switch keeps the entry until it ends
    built: set[str] = set()
    # A group slides open in a box that shows only as much as the animation has reached. As a scroll box
    # (Quasar sets overflow hidden) it scrolls to a row brought into view meanwhile (keyboard focus, find in
    # page, a test driver before its click) and carries that row along while it grows: a switch pressed
    # there is released over another element and gets no click. Clipped, every row keeps its place.
    ui.add_css(".q-expansion-item__content { overflow-y: clip !important; }")

    def refresh() -> None:
        for name, lab in rows:
            lab.set_text(value_text(name))
        for name, sw in switches:
            v = p.value(name)
            if name not in writing and v is not None and bool(v) != sw.value:
                sw.set_value(bool(v))

    def build(g: str, exp: ui.expansion) -> None:
        """A group's rows are made when it is first opened (a page of every parameter is slow)."""
        if g in built:
            return
        built.add(g)
        with exp:
            for name in groups[g]:
                if p.model.regmap[name].is_bit:
                    switches.append((name, _switch_row(name, writing)))
                else:
                    rows.append((name, _param_row(name)))
        refresh()

    for g in order:
        exp = ui.expansion(GROUP_TITLES.get(g, g.replace("_", " "))).classes("w-full").props(
            f'data-testid="group-{g}"')
        exp.on_value_change(lambda e, g=g, exp=exp: build(g, exp) if e.value else None)
        if g in ("pid_heating", "setpoint"):
            exp.set_value(True)

    ui.timer(1.0, refresh)


def _param_row(name: str) -> ui.label:
    p = panel()
    meta, tag = p.model.meta[name], p.model.regmap[name]
    with ui.row().classes("items-center w-full no-wrap"):
        with ui.column().classes("w-72 gap-0"):
            ui.label(name).classes("text-weight-medium")
            ui.label(tag.comment).classes("text-caption text-grey-7")
        current = ui.label().classes("w-28").props(f'data-testid="val-{name}"')
        if meta.min is not None and meta.max is not None:
            rng = f"{fmt(meta.min)} … {fmt(meta.max)}"
        elif meta.min is not None or meta.max is not None:
            rng = f"≥ {fmt(meta.min)}" if meta.min is not None else f"≤ {fmt(meta.max)}"
        else:
            rng = "no range"
        ui.label(f"{rng} {meta.unit}; default {fmt(meta.default)}").classes("w-56 text-caption")
        box = ui.input().props(f'dense data-testid="in-{name}"').classes("w-32")
        msg = ui.label().classes("text-negative text-caption").props(f'data-testid="msg-{name}"')

        async def send() -> None:
            value, why = number_or_error(box.value)
            if why is None:
                why = meta.check(value)
            if why is None and tag.iec_type not in ("REAL", "LREAL") and value != int(value):
                why = f"{tag.iec_type} takes whole numbers"
            if why:
                msg.set_text(f"refused: {why}; nothing written")
                return
            msg.set_text("")
            result = await p.write({name: int(value) if tag.iec_type not in ("REAL", "LREAL") else value},
                                   ENGINEER, name)
            if result is not None and not result.ok:
                msg.set_text(result.message)

        ui.button("Write", on_click=send).props(f'dense data-testid="write-{name}"')
    return current


def _switch_row(name: str, writing: set[str]) -> ui.switch:
    """A coil parameter: a switch showing the value in use; a change is written at once (engineer level, the
    name in `writing` meanwhile) and a write the PLC does not take puts the switch back with the reason."""
    p = panel()
    tag = p.model.regmap[name]
    with ui.row().classes("items-center w-full no-wrap"):
        with ui.column().classes("w-72 gap-0"):
            ui.label(name).classes("text-weight-medium")
            ui.label(tag.comment).classes("text-caption text-grey-7")
        current = p.value(name)
        sw = ui.switch(value=bool(current) if current is not None else False).props(
            f'data-testid="sw-{name}"')
        msg = ui.label().classes("text-negative text-caption").props(f'data-testid="msg-{name}"')

    async def send(e: ValueChangeEventArguments) -> None:
        on, shown = bool(e.value), p.value(name)
        if shown is None or bool(shown) == on:  # the page following the PLC, not an entry
            return
        msg.set_text("")
        writing.add(name)
        try:
            result = await p.write({name: on}, ENGINEER, f"{name} {'on' if on else 'off'}")
        finally:
            writing.discard(name)
        if result is None or not result.ok:
            if result is not None:
                msg.set_text(result.message)
            sw.set_value(bool(p.value(name)))

    sw.on_value_change(send)
    return sw


@dataclass
class TuneSession:
    """What the tuning page keeps per zone: the gain set before TUNE (restored by reject)."""

    before: dict[str, float] = field(default_factory=dict)
    started: float = 0.0
    step_start: float | None = None
    x0: float | None = None
    decided: str = ""


SESSIONS: dict[int, TuneSession] = {}


def _session(zone: int) -> TuneSession:
    """This zone's tuning session, from memory or from the database (after a panel restart)."""
    if zone not in SESSIONS:
        saved = panel().store.load_tune(zone)
        SESSIONS[zone] = TuneSession() if saved is None else TuneSession(
            before=saved[1], started=saved[0], decided=saved[2])
    return SESSIONS[zone]


def _save(zone: int, ses: TuneSession) -> None:
    SESSIONS[zone] = ses
    panel().store.save_tune(zone, ses.started, ses.before, ses.decided)


@ui.page("/tuning")
def tuning_page(zone: int = 1) -> None:
    p = panel()
    frame("Self-tuning")
    z = _zone_select(zone, "/tuning")
    gains = [r for r in GAIN_SET_ROLES if z.has(r)]
    with ui.row().classes("items-center"):
        ui.button("Start TUNE", on_click=lambda: start()).props('data-testid="tune-start"')
        ui.button("Accept", on_click=lambda: accept()).props('data-testid="tune-accept"')
        ui.button("Reject (restore previous gains)", on_click=lambda: reject()).props(
            'data-testid="tune-reject"')
    phase = ui.label().classes("text-h6").props('data-testid="tune-phase"')
    progress = ui.linear_progress(value=0, show_value=False).props("size=14px")
    err = ui.label().classes("text-negative").props('data-testid="tune-error"')
    ident = ui.label().props('data-testid="tune-ident"')
    columns = [{"name": c, "label": c, "field": c} for c in ("gain", "before TUNE", "proposed")]
    table = ui.table(columns=columns, rows=[], row_key="gain").props('data-testid="tune-table"')
    decided = ui.label().props('data-testid="tune-decided"')

    async def start() -> None:
        before = {z[r]: p.value(z[r]) for r in gains}
        if any(v is None for v in before.values()):
            ui.notify("gains not read yet", type="warning")
            return
        result = await p.write({z["mode"]: p.model.codes.modes["TUNE"]}, ENGINEER, f"TUNE zone {z.number}")
        if result is not None and result.ok:
            _save(z.number, TuneSession(before=before, started=time.time()))

    async def accept() -> None:
        ses = _session(z.number)
        if not _tuned(z) or not ses.before:
            ui.notify("nothing to accept: no tuning finished on this panel", type="warning")
            return
        level = p.level()
        from .auth import allowed

        if not allowed(level, ENGINEER):
            ui.notify(f"accept: needs the engineer level (you are {level})", type="warning")
            return
        for r in gains:
            p.store.add_audit(level, z[r], ses.before[z[r]], p.value(z[r]), "accepted", "tuned set accepted")
        ses.decided = "accepted"
        _save(z.number, ses)
        ui.notify("tuned gains accepted", type="positive")

    async def reject() -> None:
        ses = _session(z.number)
        if not ses.before:
            ui.notify("nothing to reject: no tuning started on this panel", type="warning")
            return
        result = await p.write(dict(ses.before), ENGINEER, "restore the gains from before TUNE")
        if result is not None and result.ok:
            ses.decided = "rejected: previous gains restored"
            _save(z.number, ses)

    def refresh() -> None:
        ses = _session(z.number)
        state = p.value(z["state"])
        ts = p.value(z["tune_state"]) if z.has("tune_state") else None
        tname = p.model.tune_states.get(int(ts), str(ts)) if ts is not None else "-"
        sname = p.model.codes.state_name(int(state)) if state is not None else "-"
        elapsed = f", {time.time() - ses.started:.0f} s since start" if ses.started else ""
        phase.set_text(f"state {sname}, tuning phase {tname}{elapsed}")
        progress.set_value(_progress(z, tname, ses))
        err_id = int(p.value(z["error"]) or 0) if z.has("error") else 0
        err.set_text(f"error {err_id}: {p.poller.error_text.get(err_id, '')}" if err_id else "")
        rule = p.value(z["tune_rule_used"]) if z.has("tune_rule_used") else None
        rule_text = p.model.tune_rules.get(int(rule), str(rule)) if rule is not None else "-"
        quality = ""
        order = p.value(z["tune_order"]) if z.has("tune_order") else None
        ratio = p.value(z["lag_ratio"]) if z.has("lag_ratio") else None
        if order and ratio:
            quality += f"; model: two lags, the second {ratio:.3g} x the first"
        elif order:
            quality += "; model: first order" if int(order) == 1 else f"; model: {int(order)} equal lags"
        if z.has("fit_rms") and p.value(z["fit_rms"]):
            quality += f"; fit rms {value_text(z['fit_rms'])} of the rise"
        if z.has("ms_tuned") and p.value(z["ms_tuned"]):
            quality += f"; Ms of the set {value_text(z['ms_tuned'])} (robust <= 1.6)"
        quality += _noise_and_filter(z)
        ident.set_text(f"identified: K = {value_text(z['ks']) if z.has('ks') else '-'}, "
                       f"T = {value_text(z['tg']) if z.has('tg') else '-'}, "
                       f"L = {value_text(z['tu']) if z.has('tu') else '-'}; rule used: {rule_text}{quality}")
        rows = [{"gain": z[r], "before TUNE": fmt(ses.before.get(z[r])) if ses.before else "-",
                 "proposed": value_text(z[r])} for r in gains]
        if rows != table.rows:
            table.rows = rows
        decided.set_text(ses.decided)

    refresh()
    ui.timer(0.5, refresh)


def _noise_and_filter(z: ZoneModel) -> str:
    """The sensor noise TUNE measured at rest and the actual-value filter it sized from it / the one in use
    ("" before a tuning has measured the noise)."""
    p = panel()
    if not (z.has("noise_pp") and p.value(z["noise_pp"])):
        return ""
    text = f"; sensor noise {value_text(z['noise_pp'])} peak-to-peak at rest"
    if z.has("noise_interval") and p.value(z["noise_interval"]):
        text += f", a new reading every {value_text(z['noise_interval'])}"
    if z.has("t_filter"):
        text += f", filter sized {value_text(z['t_filter'])}"
    if z.has("t_filter_used"):
        text += f", in use {value_text(z['t_filter_used'])}"
    return text


def _tuned(z: ZoneModel) -> bool:
    p = panel()
    state = p.value(z["state"])
    return state is not None and int(state) == p.model.codes.states.get("TUNED", -1)


def _progress(z: ZoneModel, phase: str, ses: TuneSession) -> float:
    """INIT/IDLE: first quarter; STEP: the share of the way X0 -> W the PLC needs (fEndTunePercent)."""
    p = panel()
    if _tuned(z) or phase == "READY":
        return 1.0
    if phase != "STEP":
        ses.step_start, ses.x0 = None, None
        return 0.1 if phase in ("INIT", "IDLE") else 0.0
    x, w = p.value(z["pv"]), p.value(z["setpoint"])
    if ses.x0 is None:
        ses.x0 = x
    end = p.value(z["end_tune_pct"]) if z.has("end_tune_pct") else 100.0
    if x is None or w is None or ses.x0 is None or not end or math.isclose(w, ses.x0):
        return 0.25
    share = (x - ses.x0) / ((w - ses.x0) * float(end) / 100.0)
    return 0.25 + 0.75 * max(0.0, min(1.0, share))
