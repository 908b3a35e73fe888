"""The neighbour search lists exactly the pairs within r_i + r_j + skin (minimum image on the
periodic axes), once each: on a box of beads placed at random, against brute force, with z not
periodic (the search walks 9 runs of three cells along z) and periodic (27 cells)."""
import pytest

import taichi_dem as td

from conftest import listed_pairs, pairs_within

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


@pytest.mark.parametrize("periodic", [[], ["x", "y"], ["z"], ["x", "y", "z"]])
def test_search_lists_every_pair_within_the_cutoff_once(periodic):
    with td.Simulation.from_text(_box_scene(periodic), arch="cpu", precision="f64") as sim:
        assert min(sim.engine.model.grid.dims) >= 3            # no thin axis: the plain stencil
        own, partner = listed_pairs(sim)
        brute = pairs_within(sim, sim.skin)
    assert len(brute) > 300                               # a dense enough box to mean something
    assert len(own) == len(set(own)), "a pair is listed twice"
    assert set(own) == brute
    assert sorted(partner) == sorted(own)                 # each pair in both rows


def test_search_rows_that_fill_or_overflow_the_candidate_scratch(monkeypatch):
    """Rows exactly as long as the scratch (the search writes each tested particle at the
    row's next slot, listed or not: past a full row it must not overwrite the last listed one)
    and rows longer than it (the scratch widens and the search repeats) list the same pairs."""
    with td.Simulation.from_text(_box_scene([]), arch="cpu", precision="f64") as sim:
        brute = pairs_within(sim, sim.skin)
        longest = int(sim.engine.state.row_count.to_numpy()[:sim.particle_count].max())
    assert longest >= 4
    for width in (longest, longest - 2):
        monkeypatch.setattr(td.engine.broadphase.Broadphase, "FIRST_SCRATCH_WIDTH", width)
        with td.Simulation.from_text(_box_scene([]), arch="cpu", precision="f64") as sim:
            own, _ = listed_pairs(sim)
            widened = sim.engine.broadphase.scratch_width
        assert set(own) == brute, f"first width {width}"
        assert (widened > width) == (width < longest)
