"""Thermal plant models for the harness (see base.py for the integrators)."""

from .base import DelayLine, Plant, PlantDisturbance, ZoneDisturbance
from .linear import Fopdt, Sopdt
from .lti import NLag, TransferFunctionPlant
from .thermal import CureMould, FormingPlatform, MarlinHotend, NonlinearHotend, TclabTwin

PLANT_MODELS: dict[str, type[Plant]] = {
    "fopdt": Fopdt,
    "sopdt": Sopdt,
    "nlag": NLag,
    "transfer_function": TransferFunctionPlant,
    "nonlinear_hotend": NonlinearHotend,
    "marlin_hotend": MarlinHotend,
    "tclab": TclabTwin,
    "forming_platform": FormingPlatform,
    "cure_mould": CureMould,
}


def array_fields(model: str) -> tuple[str, ...]:
    """Parameters of a plant model that are lists of numbers (e.g. transfer-function coefficients)."""
    return tuple(getattr(PLANT_MODELS[model], "ARRAY_FIELDS", ()))


__all__ = [
    "PLANT_MODELS",
    "array_fields",
    "CureMould",
    "DelayLine",
    "Fopdt",
    "FormingPlatform",
    "MarlinHotend",
    "NLag",
    "NonlinearHotend",
    "Plant",
    "PlantDisturbance",
    "Sopdt",
    "TclabTwin",
    "TransferFunctionPlant",
    "ZoneDisturbance",
]
