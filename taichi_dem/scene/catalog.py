"""The scene's catalog of the sections effects declare: the settings modules of the effects
that have scene keys of their own (plain Python, no Taichi), found, not listed: every package under ``taichi_dem/effects/`` with a ``settings``
module, and the heat transfer's (``taichi_dem.thermal.settings``). Importing this registers
their sections (scene/keys.py) with the loader and the schema; a new effect package is found
here without an edit.

Each module declares its Section(s) and its ``SERIES`` (the series its effect writes, with
their units: sensors/units.py). One whose whole top-level section it reads itself gives the
Section a ``reader`` (the loader keeps the result in ``Scene.settings``), and a ``builds``
function making the effect objects (effects/registry.py): the drag's [gas] (also derived from
a [thermal.gas] with ``drag``), [mobility], [viscous_damping]. [thermal] is read the same way
but kept in its own Scene field (``scene.thermal``), first: the others may read it.

The settings modules are imported by discovery (importlib), not named: they stand on the
scene's floor of the layers (docs/architecture.md "Layers"), beside their effects' kernels.
"""
from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path
from types import ModuleType

# the heat transfer's keys come first: an effect's ``derive`` may read the parsed [thermal]
_THERMAL = "taichi_dem.thermal.settings"


# where the effect packages live (found by discovery: the scene's layer names no effect)
_EFFECTS = "taichi_dem.effects"


def _effect_packages() -> list[str]:
    """The effect packages under taichi_dem/effects/ that have a settings module, by name."""
    here = Path(__file__).resolve().parent.parent / "effects"
    return sorted(f"{_EFFECTS}.{m.name}.settings" for m in pkgutil.iter_modules([str(here)])
                  if m.ispkg and (here / m.name / "settings.py").exists())


SETTINGS_MODULES: tuple[ModuleType, ...] = tuple(
    importlib.import_module(name) for name in [_THERMAL] + _effect_packages())


def settings_modules() -> tuple[ModuleType, ...]:
    """Every effect's settings module (thermal first, then the effect packages by name)."""
    return SETTINGS_MODULES


def frame_fields() -> dict:
    """{name: (unit, shape, description)}: the per-particle fields the effects add to each
    recorded frame where the particles carry them (their settings modules' FRAME_FIELDS)."""
    out = {}
    for module in SETTINGS_MODULES:
        out.update(getattr(module, "FRAME_FIELDS", {}))
    return out


def colour_fields() -> tuple:
    """The frame fields the viewers colour particles by, first choice first (COLOUR_FIELDS)."""
    return tuple(name for module in SETTINGS_MODULES
                 for name in getattr(module, "COLOUR_FIELDS", ()))


def series_views() -> dict:
    """{title: (series name patterns, ...)}: the time-series views the effects ask a viewer
    for (SERIES_VIEWS)."""
    out = {}
    for module in SETTINGS_MODULES:
        out.update(getattr(module, "SERIES_VIEWS", {}))
    return out
