from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent

SMALL_SCENE = """
[simulation]
end_time = 0.02
gravity = [0.0, 0.0, -9.81]
precision = "{precision}"
seed = 3

[domain]
min = [-0.05, -0.05, -0.01]
max = [0.05, 0.05, 0.2]

[[walls]]
name = "floor"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
rolling_friction = {rolling}

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
rolling_friction = {rolling}

[[particles]]
material = "glass"
radius = 0.004
count = {count}
region = {{ box = {{ min = [-0.04, -0.04, 0.005], max = [0.04, 0.04, 0.1] }} }}

[output]
interval = 0.005
"""


# a steel paddle turning about x (from rest, then 6 rpm from t = 0.05 s) and one glass bead on it
PLATE_SCENE = """
[simulation]
end_time = 1.0
gravity = [0.0, 0.0, -9.81]
precision = "f64"

[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5

[[bodies]]
name = "paddle"
material = "steel"
mesh = { builder = "box", min = [-0.02, -0.01, -0.005], max = [0.02, 0.06, 0.0], normals = "outward" }
motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = [[0.0, "0 rpm"], [0.05, "6 rpm"]] } }

[[particles]]
material = "glass"
radius = 0.004
count = 1
region = { box = { min = [-0.01, 0.03, 0.001], max = [0.01, 0.05, 0.02] } }

[output]
interval = 0.01
"""


@pytest.fixture
def small_scene_text():
    def make(precision="f64", rolling=0.05, count=200):
        return SMALL_SCENE.format(precision=precision, rolling=rolling, count=count)
    return make


def listed_pairs(sim) -> tuple[list, list]:
    """The neighbour lists as (owner id, partner id) pairs: those of the owned entries, and
    those of the partner entries (each pair should stand once in each)."""
    e = sim.engine
    s = e.state
    n = e.count
    start, owned = s.row_start.to_numpy()[:n], s.row_owned.to_numpy()[:n]
    count = s.row_count.to_numpy()[:n]
    ids = s.particle_id.to_numpy()[:n]
    nb = e.pairs.neighbour.to_numpy()
    own = [(int(ids[i]), int(ids[nb[k]])) for i in range(n) for k in range(start[i], start[i] + owned[i])]
    partner = [(int(ids[nb[k]]), int(ids[i])) for i in range(n)
               for k in range(start[i] + owned[i], start[i] + count[i])]
    return own, partner


def pairs_within(sim, cutoff_extra: float) -> set:
    """Brute force: (smaller id, larger id) of the pairs closer than r_i + r_j +
    ``cutoff_extra`` (m), by the minimum image on the periodic axes."""
    e = sim.engine
    s = e.state
    n = e.count
    x = s.position.to_numpy()[:n].astype(float)
    r = s.radius.to_numpy()[:n].astype(float)
    ids = s.particle_id.to_numpy()[:n]
    d = x[:, None, :] - x[None, :, :]
    for k in range(3):
        if e.grid.periodic[k]:
            d[..., k] -= e.grid.span[k] * np.round(d[..., k] / e.grid.span[k])
    close = np.linalg.norm(d, axis=2) < r[:, None] + r[None, :] + cutoff_extra
    i, j = np.nonzero(close & (ids[:, None] < ids[None, :]))
    return {(int(ids[a]), int(ids[b])) for a, b in zip(i, j)}
