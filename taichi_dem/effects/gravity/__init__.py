"""Uniform gravity: every moving particle accelerates at g. On wherever the scene's
``[simulation] gravity`` is nonzero (the default, 9.81 m/s^2 down).

``settings.py``: the key it adds to [simulation], its settings and its bounds for the time
step and the divergence guard (plain Python); ``effect.py``: the ``Gravity`` effect (Taichi),
loaded on first use.
"""
from .settings import SECTION, GravitySettings  # noqa: F401
