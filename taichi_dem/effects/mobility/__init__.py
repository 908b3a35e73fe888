"""Mobility: skip the contacts and the integration of particles that do not move.

``settings.py``: the [mobility] keys, ``MobilitySettings`` and their checks (plain Python);
``effect.py``: the ``Mobility`` effect (its fields and kernels; Taichi), loaded on first use.
"""
from .settings import MobilitySettings, SECTION  # noqa: F401


def __getattr__(name):
    if name in ("Mobility", "INACTIVE", "ACTIVE", "MOBILE", "EMPTY"):
        from . import effect
        return getattr(effect, name)
    raise AttributeError(f"module 'taichi_dem.effects.mobility' has no attribute {name!r}")
