"""The scene's catalog of the sections effects declare: the settings modules of the effects
that have scene keys of their own (plain Python, no Taichi), found, not listed: every package under ``taichi_dem/effects/`` with a ``settings``
module, and the heat transfer's (``taichi_dem.thermal.settings``). Importing this registers
their sections (scene/keys.py) with the loader and the schema; a new effect package is found
here without an edit.

Each module declares its Section(s) and its ``SERIES`` (the series its effect writes, with
their units: sensors/units.py). One whose whole top-level section it reads itself gives the
Section a ``reader`` (the loader keeps the result in ``Scene.settings``), and a ``builds``
function making the effect objects (effects/registry.py): the drag's [gas] (also derived from
a [thermal.gas] with ``drag``), [mobility], [viscous_damping], [thermal]. A section that
reads another's settings says so (``Section.after``), and is read after it.

The settings modules are imported by discovery (importlib), not named: they stand on the
scene's floor of the layers (docs/architecture.md "Layers"), beside their effects' kernels.
"""
from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path
from types import ModuleType

# where the effect packages live (found by discovery: the scene's layer names no effect)
_EFFECTS = "taichi_dem.effects"


def _effect_packages() -> list[str]:
    """The effect packages under taichi_dem/effects/ that have a settings module, by name."""
    here = Path(__file__).resolve().parent.parent / "effects"
    return sorted(f"{_EFFECTS}.{m.name}.settings" for m in pkgutil.iter_modules([str(here)])
                  if m.ispkg and (here / m.name / "settings.py").exists())


def _namespace_packages() -> list[str]:
    """The packages installed into the namespace from the checkout's top-level folders
    (pyproject.toml's package-dir: the heat transfer's) that have a settings module, by name.
    Found by their files, not imported to look: the scene's floor imports no Taichi."""
    namespace = sys.modules[__name__.split(".")[0]]     # (imported: this module is in it)
    out = []
    for m in pkgutil.iter_modules(namespace.__path__):
        folder = Path(getattr(m.module_finder, "path", "")) / m.name
        if m.ispkg and (folder / "settings.py").exists():
            out.append(f"taichi_dem.{m.name}.settings")
    return sorted(out)


# the effect packages first, then the namespace's (whose effects the step lists after theirs:
# effects/registry.py builds them in this order)
SETTINGS_MODULES: tuple[ModuleType, ...] = tuple(
    importlib.import_module(name) for name in _effect_packages() + _namespace_packages())


def settings_modules() -> tuple[ModuleType, ...]:
    """Every effect's settings module (the effect packages under taichi_dem/effects/, then
    the namespace's packages, each by name)."""
    return SETTINGS_MODULES


def frame_fields() -> dict:
    """{name: (unit, shape, description)}: the per-particle fields the effects add to each
    recorded frame where the particles carry them (their settings modules' FRAME_FIELDS)."""
    out = {}
    for module in SETTINGS_MODULES:
        out.update(getattr(module, "FRAME_FIELDS", {}))
    return out


def frame_field_values() -> dict:
    """{name: "positive" | "nonnegative" | "finite"}: what a fill started from an earlier
    run's frame accepts of each field the effects add to the frames (FRAME_FIELD_VALUES;
    "finite" where a module does not say)."""
    out = {name: "finite" for name in frame_fields()}
    for module in SETTINGS_MODULES:
        out.update(getattr(module, "FRAME_FIELD_VALUES", {}))
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
