"""Shared state of the panel and the frame every page uses: header, navigation, PLC banner, login."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from nicegui import app, ui

from .auth import ENGINEER, OPERATOR, VIEWER, Access, allowed
from .model import PanelModel, fmt
from .poller import Poller, WriteResult
from .store import Store

PAGES = (("/", "Overview"), ("/trend", "Trend"), ("/alarms", "Alarms"), ("/params", "Parameters"),
         ("/tuning", "Tuning"), ("/fuzzy", "Fuzzy"), ("/diag", "Diagnostics"))
UI_PERIOD_S = 0.1  # page refresh (the poll loop runs on its own)
STALE_CLASS = "text-grey-5"


@dataclass
class Panel:
    model: PanelModel
    poller: Poller
    store: Store
    access: Access
    plc_label: str
    sessions: dict[str, str] = field(default_factory=dict)  # browser id -> level

    def level(self) -> str:
        try:
            return self.sessions.get(app.storage.browser["id"], VIEWER)
        except (RuntimeError, KeyError):
            return VIEWER

    def set_level(self, level: str) -> None:
        self.sessions[app.storage.browser["id"]] = level

    def value(self, name: str):
        return self.poller.values.get(name)

    async def write(self, values: dict, needed: str, what: str) -> WriteResult | None:
        """Write from a page: level check, then the poller (read back + audit); the outcome is notified."""
        level = self.level()
        if not allowed(level, needed):
            msg = f"{what}: needs the {needed} level (you are {level})"
            self.store.add_audit(level, ",".join(values), None, values, "denied", msg)
            ui.notify(msg, type="warning")
            return None
        why = self.poller.stale_reason()
        if why:
            msg = f"{what}: {why}, nothing written"
            ui.notify(msg, type="negative")
            return None
        result = await self.poller.write(values, level)
        ui.notify(f"{what}: {result.message}", type="positive" if result.ok else "negative",
                  multi_line=True, timeout=8000)
        return result


PANEL: Panel | None = None


def panel() -> Panel:
    assert PANEL is not None, "the panel is not configured"
    return PANEL


def number_or_error(text: object) -> tuple[float | None, str | None]:
    """Parse a page entry: a finite number, else the reason."""
    if text is None or (isinstance(text, str) and not text.strip()):
        return None, "enter a number"
    try:
        value = float(str(text).replace(",", "."))
    except ValueError:
        return None, f"{text!r} is not a number"
    if not math.isfinite(value):
        return None, "not a finite number"
    return value, None


def frame(title: str) -> ui.element:
    """Header + navigation + PLC banner; returns the page's content column."""
    p = panel()
    ui.add_head_html('<script src="/hmi-static/trend.js"></script>')
    with ui.header().classes("items-center justify-between bg-blue-grey-9 q-py-xs"):
        with ui.row().classes("items-center gap-2"):
            ui.label("ThermoST").classes("text-h6")
            for path, name in PAGES:
                ui.link(name, path).classes("text-white q-px-xs").props(f'data-testid="nav-{name.lower()}"')
        with ui.row().classes("items-center gap-2"):
            conn = ui.label().props('data-testid="conn"')
            level_label = ui.label().props('data-testid="level"')
            ui.button("Login", on_click=login_dialog).props('flat color=white data-testid="login"')
            ui.button("Logout", on_click=lambda: (p.set_level(VIEWER), ui.navigate.reload())).props(
                "flat color=white")
    banner = ui.label().classes("w-full bg-red-8 text-white q-pa-sm text-weight-bold").props(
        'data-testid="banner"')

    def refresh() -> None:
        d = p.poller.diag
        stale = p.poller.stale
        conn.set_text(f"PLC {p.plc_label}: " + ("stale" if stale else "online"))
        level_label.set_text(f"level: {p.level()}")
        banner.set_visibility(stale)
        if stale:
            age = time.time() - d.last_ok if d.last_ok else math.inf
            banner.set_text(f"PLC not reachable ({d.error or 'no answer'}); values shown are "
                            f"{'never read' if math.isinf(age) else f'{age:.0f} s old'}; reconnecting…")

    refresh()
    ui.timer(0.5, refresh)
    ui.label(title).classes("text-h5 q-mt-sm")
    return ui.column().classes("w-full")


def login_dialog() -> None:
    p = panel()
    with ui.dialog() as dialog, ui.card():
        ui.label("Access level")
        level = ui.select([OPERATOR, ENGINEER], value=OPERATOR).props('data-testid="login-level"')
        password = ui.input("password", password=True).props('data-testid="login-password"')
        msg = ui.label().classes("text-negative").props('data-testid="login-msg"')

        def submit() -> None:
            why = p.access.login(level.value, password.value or "")
            p.store.add_audit(level.value, "login", p.level(), level.value, "refused" if why else "accepted",
                              why or "")
            if why:
                msg.set_text(why)
                return
            p.set_level(level.value)
            dialog.close()
            ui.navigate.reload()

        ui.button("Log in", on_click=submit).props('data-testid="login-submit"')
    dialog.open()


def live_text(label: ui.label, getter, stale_aware: bool = True) -> None:
    """Set a label's text and grey it out while the PLC is not reachable."""
    label.set_text(getter())
    if stale_aware:
        label.classes(add=STALE_CLASS) if panel().poller.stale else label.classes(remove=STALE_CLASS)


def value_text(name: str | None, decimals: int | None = None, unit: bool = True) -> str:
    p = panel()
    if name is None:
        return "-"
    v = p.value(name)
    meta = p.model.meta.get(name)
    if v is None:
        return "-"
    if meta and meta.enum and not isinstance(v, float):
        return meta.enum.get(int(v), str(v))
    d = decimals if decimals is not None else (meta.decimals if meta else 2)
    text = fmt(float(v), d) if isinstance(v, float) else str(v)
    return f"{text} {meta.unit}" if unit and meta and meta.unit else text
