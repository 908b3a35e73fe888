"""The settings modules of the effects that have scene keys of their own (plain Python, no
Taichi). Importing this registers their sections (scene/keys.py) with the loader and the
schema; a new effect with a section of its own adds its settings module here, once.

Each module declares its Section(s); one whose whole top-level section it reads itself gives
the Section a ``reader`` (the loader then keeps the result in ``Scene.settings``). [thermal],
[gas] and [mobility] predate that and keep their own Scene fields (``scene.thermal``,
``scene.drag``, ``scene.mobility``), read by the loader in a fixed order (drag after thermal).
"""
from taichi_dem.thermal import settings as thermal_settings  # noqa: F401

from .drag import settings as drag_settings  # noqa: F401
from .mobility import settings as mobility_settings  # noqa: F401
from .viscous_damping import settings as viscous_damping_settings  # noqa: F401
