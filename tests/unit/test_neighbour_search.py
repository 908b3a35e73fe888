"""The neighbour search lists exactly the pairs within r_i + r_j + skin (minimum image on the
periodic axes), once each: on a box of beads placed at random, against brute force, with z not
periodic (the search walks 9 runs of three cells along z) and periodic (27 cells)."""
import numpy as np
import pytest

import taichi_dem as td

R = 0.0015


def _box_scene(periodic: list[str]) -> str:
    return f"""
[simulation]
end_time = 0.01
gravity = [0.0, 0.0, 0.0]
precision = "f64"
seed = 5
[domain]
min = [0.0, 0.0, 0.0]
max = [0.03, 0.027, 0.024]
periodic = {periodic!r}
[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25
[[interactions]]
pair = ["glass", "glass"]
restitution = 0.9
friction = 0.2
[[particles]]
material = "glass"
radius = {R}
count = 500
region = {{ box = {{ min = [0.0, 0.0, 0.0], max = [0.03, 0.027, 0.024] }} }}
[output]
interval = 0.005
"""


def _listed(sim) -> list[tuple[int, int]]:
    """(owner id, partner id) of every owned neighbour entry, and the partner entries."""
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


def _within(sim) -> set[tuple[int, int]]:
    """Brute force: (smaller id, larger id) closer than r_i + r_j + skin, minimum image."""
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
    close = np.linalg.norm(d, axis=2) < r[:, None] + r[None, :] + sim.skin
    i, j = np.nonzero(close & (ids[:, None] < ids[None, :]))
    return {(int(ids[a]), int(ids[b])) for a, b in zip(i, j)}


@pytest.mark.parametrize("periodic", [[], ["x", "y"], ["z"], ["x", "y", "z"]])
def test_search_lists_every_pair_within_the_cutoff_once(periodic):
    with td.Simulation.from_text(_box_scene(periodic), arch="cpu", precision="f64") as sim:
        assert min(sim.engine.grid.dims) >= 3            # no thin axis: the plain stencil
        own, partner = _listed(sim)
        brute = _within(sim)
    assert len(brute) > 300                               # a dense enough box to mean something
    assert len(own) == len(set(own)), "a pair is listed twice"
    assert set(own) == brute
    assert sorted(partner) == sorted(own)                 # each pair in both rows
