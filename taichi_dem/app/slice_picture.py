"""A picture of a slice's bed at the end of its run (``taichi-dem map --pictures``): the
cross-section seen along the axis, each sphere drawn at its size and coloured by its axial
speed, the bodies' surfaces in grey, so a hold-up's bed (how high it stands, whether it buries
the shaft, where the paddles leave it) can be seen beside its figures."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def draw_bed(sim, geometry, up: np.ndarray, horizontal: np.ndarray, path: Path,
             title: str) -> Path:
    """``path`` (PNG): the particles of ``sim`` projected on the plane across the slice's
    axis (``horizontal`` to the right, ``up`` against gravity; m), coloured by axial speed
    (mm/s), with the bodies' vertices; returns it."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.patches import Circle

    p = sim.particles()
    moving = ~p["fixed"]
    x, v, r = p["position"][moving], p["velocity"][moving], p["radius"][moving]
    rel = x - geometry.axis_point
    u, w = rel @ horizontal, rel @ up
    axial = 1e3 * (v @ geometry.axis_direction)
    fig, ax = plt.subplots(figsize=(6.4, 6.0))
    # deepest first, so the spheres nearest the viewer (the slice's +axis end) lie on top
    order = np.argsort(rel @ geometry.axis_direction)
    circles = PatchCollection([Circle((u[i], w[i]), r[i]) for i in order], cmap="coolwarm",
                              linewidths=0.0)
    limit = float(np.percentile(np.abs(axial), 98)) if len(axial) else 1.0
    circles.set_array(axial[order])
    circles.set_clim(-limit, limit)
    ax.add_collection(circles)
    poses = sim.body_poses()
    for body in sim.scene.bodies:
        b = np.asarray(body.vertices, float)
        if body.name in poses:          # where the body stands now (the shaft has turned)
            rotation, translation = poses[body.name]
            b = b @ np.asarray(rotation).T + np.asarray(translation)
        b = b - geometry.axis_point
        flat = np.stack([b @ horizontal, b @ up], axis=1)
        faces = np.asarray(body.faces)
        edges = np.concatenate([flat[faces[:, [0, 1]]], flat[faces[:, [1, 2]]],
                                flat[faces[:, [2, 0]]]])
        ax.add_collection(LineCollection(edges, colors="0.35", linewidths=0.4, zorder=3))
    R = geometry.shell_radius
    t = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(R * np.cos(t), R * np.sin(t), "-", color="0.3", lw=1.0)
    ax.set_xlim(-1.05 * R, 1.05 * R)
    ax.set_ylim(-1.05 * R, 1.05 * R)
    ax.set_aspect("equal")
    ax.set_xlabel("across (m)")
    ax.set_ylabel("up (m)")
    ax.set_title(title, fontsize=9)
    fig.colorbar(circles, ax=ax, label="axial speed (mm/s)", shrink=0.8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
