"""Each particle's mesh candidates placed once per step (bodies/mesh_contacts.py
``make_place_candidates``): what the shields and the gather's mesh contacts read instead of
placing the triangle themselves. After steps of the periodic flighted drum slice (its shell's
strips span the period, so the image nearest a triangle is not always the particle itself)
in f64, every candidate entry holds its triangle in the world frame now (R (x_ref - p) + p +
offset from the body's frame), the particle's periodic image nearest that triangle (found
here by brute force over the images one period either side, with trimesh's closest point)
and that image's side of the triangle's plane, to round-off (1e-12 m; the coordinates are
~0.05 m)."""
from pathlib import Path

import numpy as np
import trimesh

import taichi_dem

SCENE = Path(__file__).with_name("slice_drum.toml")


def test_candidates_hold_the_world_triangle_and_the_nearest_image():
    text = SCENE.read_text().replace('precision = "f32"', 'precision = "f64"')
    with taichi_dem.Simulation.from_text(text, base_dir=str(SCENE.parent), h5="") as sim:
        sim.run(0.25)          # the beads fell onto the shell and ride with it
        e = sim.engine
        m = e.mesh
        n = e.count
        position = e.state.position.to_numpy()[:n]
        start, count = m.mesh_start.to_numpy()[:n], m.mesh_count.to_numpy()[:n]
        tri = m.mesh_tri.to_numpy()
        a, e1, e2 = (m.candidate_a.to_numpy(), m.candidate_e1.to_numpy(),
                     m.candidate_e2.to_numpy())
        image, side = m.candidate_image.to_numpy(), m.candidate_side.to_numpy()
        rotation, pivot, offset = (m.frames.rotation.to_numpy(), m.frames.axis_point.to_numpy(),
                                   m.frames.offset.to_numpy())
        reference = m.triangles._tris
        owner = m.triangles.owner
        period = float(e.model.grid.span[0])
    entries = [(i, k) for i in range(n) for k in range(start[i], start[i] + count[i])]
    assert len(entries) > 50                     # beads on the shell and the flights (123)
    shifted = 0
    for i, k in entries:
        t, b = tri[k], owner[tri[k]]
        world = (reference[t] - pivot[b]) @ rotation[b].T + pivot[b] + offset[b]
        assert np.allclose(a[k], world[0], rtol=0.0, atol=1e-12)
        assert np.allclose(e1[k], world[1] - world[0], rtol=0.0, atol=1e-12)
        assert np.allclose(e2[k], world[2] - world[0], rtol=0.0, atol=1e-12)
        images = position[i] + np.array([[s * period, 0.0, 0.0] for s in (-1, 0, 1)])
        nearest = trimesh.triangles.closest_point(np.repeat(world[None], 3, axis=0), images)
        best = images[np.argmin(np.linalg.norm(images - nearest, axis=1))]
        assert np.allclose(image[k], best, rtol=0.0, atol=1e-12)
        shifted += int(not np.allclose(best, position[i]))
        normal = np.cross(world[1] - world[0], world[2] - world[0])
        assert abs(side[k] - (best - world[0]) @ normal) < 1e-12 * np.linalg.norm(normal)
    assert shifted > 0      # some beads' nearest image lies across the period (15 of 123 here)
