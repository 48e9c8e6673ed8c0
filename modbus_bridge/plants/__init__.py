"""Thermal plant models for the harness (see base.py for the integrators)."""

from .base import DelayLine, Plant, PlantDisturbance, ZoneDisturbance
from .linear import Fopdt, Sopdt
from .thermal import CureMould, FormingPlatform, MarlinHotend, NonlinearHotend, TclabTwin

PLANT_MODELS: dict[str, type[Plant]] = {
    "fopdt": Fopdt,
    "sopdt": Sopdt,
    "nonlinear_hotend": NonlinearHotend,
    "marlin_hotend": MarlinHotend,
    "tclab": TclabTwin,
    "forming_platform": FormingPlatform,
    "cure_mould": CureMould,
}

__all__ = [
    "PLANT_MODELS",
    "CureMould",
    "DelayLine",
    "Fopdt",
    "FormingPlatform",
    "MarlinHotend",
    "NonlinearHotend",
    "Plant",
    "PlantDisturbance",
    "Sopdt",
    "TclabTwin",
    "ZoneDisturbance",
]
