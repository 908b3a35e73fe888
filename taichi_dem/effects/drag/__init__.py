"""Gas drag on the particles, one-way coupled.

``settings.py``: the mechanics-only [gas] keys, ``DragSettings`` (plain Python);
``effect.py``: the ``Drag`` effect (its per-cell solid volume and kernels; Taichi), loaded on
first use.
"""
from .settings import DragSettings, SECTION  # noqa: F401


def __getattr__(name):
    if name == "Drag":
        from .effect import Drag
        return Drag
    raise AttributeError(f"module 'taichi_dem.effects.drag' has no attribute {name!r}")
