"""From a scene to what the engine needs, on the host (numpy, no Taichi): the initial particles
(placement.py), pair tables of equivalent moduli and damping (pair_tables.py, restitution.py),
the time step and Verlet skin (timestep.py)."""
