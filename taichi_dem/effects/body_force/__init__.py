"""A uniform body force per unit mass on the particles, scaled per material: the pull of a
field on the fraction of the feed that answers to it (the ferrous fraction in a magnetic
separator, taken as a uniform field), or a change of gravity for one material. Off unless a
scene has [body_force].

``settings.py``: the [body_force] keys, the per-material ``body_force_factor``, the series
and the bound on the acceleration (plain Python); ``effect.py``: the ``BodyForce`` effect
(Taichi), loaded on first use. This package is the worked example of docs/architecture.md.
"""
from .settings import SECTION, BodyForceSettings  # noqa: F401
