"""Effects: each physical effect is one module (or package) with one job; the stepper composes
the ones a scene enables.

``enabled_effects(scene)`` (registry.py) builds the effect objects (base.py: stage, fields,
pair tables, kernels) in step order; the engine allocates what they declare and unrolls them
at compile time (``ti.static``): an effect not in the tuple is neither allocated, compiled
nor run. Thermal effects come from ``thermal/effects.py``, only for a scene with [thermal].
``taichi-dem check`` prints the tuple.

An effect with scene keys of its own is a package: ``settings.py`` declares its section
(scene/keys.py: each key's type, unit, default, range and description), its settings
dataclass and the cross-key checks, in plain Python; ``effect.py`` holds the Effect (fields,
kernels). The loader and the schema import the settings only, so reading a scene never
imports Taichi; that is why this package's names are loaded on first use.
"""
from __future__ import annotations

__all__ = ["enabled_effects", "effect_names", "Effect"]


def __getattr__(name):
    if name in ("enabled_effects", "effect_names"):
        from . import registry
        return getattr(registry, name)
    if name == "Effect":
        from .base import Effect
        return Effect
    raise AttributeError(f"module 'taichi_dem.effects' has no attribute {name!r}")
