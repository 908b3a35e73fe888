"""Viscous background damping (LIGGGHTS's ``fix viscous``): every moving particle's velocity
relaxes towards rest, a = -v / tau. For settling a bed quickly before the run that matters;
it is not physics of the granular flow, so it is off unless a scene has [viscous_damping].

``settings.py``: the [viscous_damping] keys and ``DampingSettings`` (plain Python);
``effect.py``: the ``ViscousDamping`` effect (a particle stage; Taichi), loaded on first use.
An effect is its package and its tests (tests/verification/test_viscous_damping.py);
scene/catalog.py finds it.
"""
from .settings import SECTION, DampingSettings  # noqa: F401
