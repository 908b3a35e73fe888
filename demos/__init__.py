"""The bundled demo scenes (``taichi-dem demo NAME``), installed as package data of
``taichi_dem.demos`` so that an installed copy finds them without a source checkout."""
