"""Particle-triangle contacts against the analytic plane and statics (issue 3).

1. Spheres at rest on a triangulated floor - over a face, on an edge shared by two triangles,
   on a vertex shared by six - sit at the static Hertz overlap of an analytic plane,
   d = (3 m g / (4 E* sqrt(R)))^(2/3), and the body carries their weight. A missing
   de-duplication would count the edge contact twice and the vertex contact six times (the
   overlap would then be 2^(-2/3) or 6^(-2/3) of the plane's); asserted to 1e-6 relative, the
   residual of the damped settling after 0.2 s in f64.
2. A sphere rolling without slip across many triangle edges and vertices keeps its speed: no
   horizontal force acts on a rolling sphere on a flat floor, so v stays v0 exactly on the
   analytic plane; on the mesh a spurious edge contact or a lost tangential history at a
   triangle change would show as a bump. Asserted: the speed constant to 1e-6 v0 along 0.1 m
   (about 10 edge and vertex crossings) and the same speed (1e-9 m/s) and trajectory (1e-9 m)
   as on the analytic plane.
3. A particle resting on a horizontal plate at lever arm L from the rotation axis loads the
   shaft with the axial torque -m g L (torque on the body, about +x). The body load is summed
   from the contact force at the overlap centre, which lies exactly at y = L: asserted to 1e-6.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import geometry
import taichi_dem
import dem_helpers as h

R = 0.005
GLASS = dict(density=2500.0, youngs_modulus=1.0e7, poisson_ratio=0.25)
STEEL = dict(density=7800.0, youngs_modulus=2.0e11, poisson_ratio=0.3)
G = 9.81


def _floor_spec():
    # the top face of a thin box, cut into triangles no longer than 2 cm
    return {"builder": "box", "min": [-0.06, -0.06, -0.01], "max": [0.06, 0.06, 0.0],
            "normals": "outward", "max_edge": 0.02}


def _toml_table(spec) -> str:
    items = []
    for k, v in spec.items():
        items.append(f"{k} = {h.vec(v) if isinstance(v, list) else (repr(v) if not isinstance(v, str) else chr(34) + v + chr(34))}")
    return "{ " + ", ".join(items) + " }"


def _body(name, spec, material="steel", motion="") -> str:
    s = f"[[bodies]]\nname = \"{name}\"\nmaterial = \"{material}\"\nmesh = {_toml_table(spec)}\n"
    if motion:
        s += f"motion = {motion}\n"
    return s + "\n"


def _static_overlap(radius, density):
    m = h.sphere_mass(radius, density)
    e_eff = h.youngs_eff(GLASS["youngs_modulus"], GLASS["poisson_ratio"],
                         STEEL["youngs_modulus"], STEEL["poisson_ratio"])
    return (3.0 * m * G / (4.0 * e_eff * math.sqrt(radius))) ** (2.0 / 3.0), m


def _top_triangles():
    mesh = geometry.build_mesh(_floor_spec())
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    top = f[np.all(np.abs(v[f][:, :, 2]) < 1e-12, axis=1)]
    return v, top


def test_sphere_at_rest_on_face_edge_and_vertex(tmp_path):
    v, top = _top_triangles()
    centroid = v[top[len(top) // 2]].mean(axis=0)
    # an interior edge (shared by two top triangles) and an interior vertex (shared by most)
    edges = {}
    for tri in top:
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges.setdefault(tuple(sorted((a, b))), []).append(tri)
    shared = [e for e, ts in edges.items() if len(ts) == 2
              and np.all(np.abs(v[list(e)][:, :2]) < 0.04)]
    edge_mid = v[list(shared[0])].mean(axis=0)
    counts = np.bincount(top.ravel(), minlength=len(v))
    inner = [k for k in np.argsort(-counts) if np.all(np.abs(v[k][:2]) < 0.04)]
    vertex = v[inner[0]]
    assert counts[inner[0]] >= 4, "the chosen vertex is shared by several triangles"
    overlap, mass = _static_overlap(R, GLASS["density"])
    spots = [centroid, edge_mid, vertex]
    # far enough apart not to touch each other
    assert min(np.linalg.norm((a - b)[:2]) for i, a in enumerate(spots) for b in spots[i + 1:]) > 2 * R
    positions = [[p[0], p[1], R - overlap] for p in spots]
    text = (h.header(gravity=(0, 0, -G), lo=(-0.07, -0.07, -0.02), hi=(0.07, 0.07, 0.05))
            + h.material("glass", **GLASS) + h.material("steel", **STEEL)
            + h.interaction("glass", "glass", 0.5, 0.5) + h.interaction("glass", "steel", 0.5, 0.5)
            + _body("floor", _floor_spec())
            + h.csv_fill(tmp_path, "rest.csv", "glass", positions, R))
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(0.2)
        p = sim.particles()
        force = sim.series["bodies/floor/force"][-1]
    achieved = R - p["position"][:, 2]
    print(f"\n  static overlap: plane {overlap:.6e} m; face/edge/vertex {achieved}")
    assert achieved == pytest.approx(np.full(3, overlap), rel=1e-6)
    assert force[2] == pytest.approx(-3 * mass * G, rel=1e-6)


def test_rolling_across_edges_keeps_its_speed(tmp_path):
    v0 = 0.1
    overlap, _ = _static_overlap(R, GLASS["density"])
    start = [-0.05, 0.0123, R - overlap]           # a path crossing many edges and vertices
    common = (h.header(gravity=(0, 0, -G), lo=(-0.07, -0.07, -0.02), hi=(0.07, 0.07, 0.05))
              + h.material("glass", **GLASS) + h.material("steel", **STEEL)
              + h.interaction("glass", "glass", 0.5, 0.5) + h.interaction("glass", "steel", 0.5, 0.5))
    fill = h.csv_fill(tmp_path, "roll.csv", "glass", [start], R, [[v0, 0, 0]], [[0, v0 / R, 0]])
    runs = {}
    for name, geometry_text in (("mesh", _body("floor", _floor_spec())),
                                ("plane", h.wall("floor", (0, 0, 0), (0, 0, 1), "steel"))):
        with taichi_dem.Simulation.from_text(common + geometry_text + fill, base_dir=str(tmp_path),
                                             precision="f64") as sim:
            speeds, xs = [], []
            steps = int(round(1.0 / sim.dt / 200))
            while sim.time < 1.0:
                sim.step(steps)
                p = sim.particles()
                speeds.append(np.linalg.norm(p["velocity"][0]))
                xs.append(p["position"][0].copy())
            runs[name] = (np.array(speeds), np.array(xs))
    speeds, xs = runs["mesh"]
    settled = speeds[1:]
    print(f"\n  rolling over the mesh: speed varies by {np.ptp(settled) / v0:.2e} of v0 after the "
          f"first sample, differs from the plane run by {np.abs(speeds - runs['plane'][0]).max():.2e} m/s, "
          f"position by {np.abs(xs - runs['plane'][1]).max():.2e} m; travelled {xs[-1, 0] - start[0]:.3f} m")
    assert xs[-1, 0] - start[0] > 0.09
    # w0 = v0/R rolls on the contact radius R - d/2: a slip of d/(2R) = 1.6e-4 settles at once
    # (the same on the plane); after it the speed is constant
    assert np.ptp(settled) < 1e-6 * v0
    assert np.abs(speeds - runs["plane"][0]).max() < 1e-9
    assert np.abs(xs - runs["plane"][1]).max() < 1e-9


def test_lever_arm_loads_the_shaft(tmp_path):
    lever = 0.04
    overlap, mass = _static_overlap(R, GLASS["density"])
    plate = {"builder": "box", "min": [-0.02, -0.01, -0.005], "max": [0.02, 0.06, 0.0],
             "normals": "outward"}
    motion = ("{ rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = 0.0 } }")
    text = (h.header(gravity=(0, 0, -G), lo=(-0.07, -0.07, -0.02), hi=(0.07, 0.07, 0.05))
            + h.material("glass", **GLASS) + h.material("steel", **STEEL)
            + h.interaction("glass", "glass", 0.5, 0.5) + h.interaction("glass", "steel", 0.5, 0.5)
            + _body("paddle", plate, motion=motion)
            + h.csv_fill(tmp_path, "lever.csv", "glass", [[0.0, lever, R - overlap]], R))
    with taichi_dem.Simulation.from_text(text, base_dir=str(tmp_path), precision="f64") as sim:
        sim.run(0.2)
        torque = sim.series["bodies/paddle/axial_torque"][-1]
    print(f"\n  axial torque {torque:.6e} N m, -m g L = {-mass * G * lever:.6e} N m")
    assert torque == pytest.approx(-mass * G * lever, rel=1e-6)
