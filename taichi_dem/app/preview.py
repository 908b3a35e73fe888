"""``taichi-dem check SCENE --preview PNG``: a picture of the scene at t = 0 before anything is
compiled or run - the initial particles where the placement puts them, the bodies' meshes,
the factories' and outlets' regions and the domain box - so that a flipped normal, a fill in
the wrong place or a factory behind a wall is seen before a run is spent on it. matplotlib
only (Agg); no Taichi.

Two views side by side: a perspective one, and one looking along the first body's axis (the
drum or shaft axis: the cross-section an engineer checks), or down the z axis without bodies.
Particles are coloured by material; their marker size follows their radius on the page.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

# material colours (tab10), factories green, outlets red
_REGION_COLOURS = {"factory": "tab:green", "outlet": "tab:red"}


def _region_lines(region, segments: int = 48) -> list[np.ndarray]:
    """Polylines (k, 3) outlining a box or a cylinder region, m."""
    if region.kind == "box":
        lo, hi = np.asarray(region.box_min, float), np.asarray(region.box_max, float)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        edges = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6),
                 (5, 7), (6, 7)]
        return [corners[list(e)] for e in edges]
    p0 = np.asarray(region.axis_point, float)
    d = np.asarray(region.axis_direction, float)
    d = d / np.linalg.norm(d)
    u = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    phi = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    ring = region.radius * (np.outer(np.cos(phi), u) + np.outer(np.sin(phi), v))
    p1 = p0 + d * region.length
    lines = [p0 + ring, p1 + ring]
    for k in range(0, segments, segments // 4):
        lines.append(np.array([p0 + ring[k], p1 + ring[k]]))
    return lines


def _view_basis(scene) -> tuple[np.ndarray, np.ndarray, str]:
    """(e1, e2, title) of the section view: across the first body's axis, else from above."""
    if scene.bodies:
        axis = np.asarray(scene.bodies[0].motion.axis_direction, float)
        axis = axis / np.linalg.norm(axis)
        up = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = np.cross(up, axis)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis, e1)
        return e1, e2, f"along the axis of '{scene.bodies[0].name}'"
    return np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), "from above (z)"


def write_preview(scene, path, *, dpi: int = 100, seed=None) -> Path:
    """Draw ``scene`` at t = 0 into the PNG ``path``; returns its path. The particles are
    placed as a run places them (the scene's seed, or ``seed``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from ..setup.placement import place_fills

    rng = np.random.default_rng(scene.simulation.seed if seed is None else seed)
    placed = place_fills(scene, rng)
    lo, hi = np.asarray(scene.domain.min, float), np.asarray(scene.domain.max, float)
    fig = plt.figure(figsize=(12, 6))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    e1, e2, section = _view_basis(scene)
    colours = plt.get_cmap("tab10")
    names = list(placed.materials) or sorted(scene.materials)
    section_particles = []          # drawn last, once the section's scale on the page is known

    # particles, by material
    for m, name in enumerate(names):
        sel = placed.material == m
        if not np.any(sel):
            continue
        p, r = placed.position[sel], placed.radius[sel]
        ax3.scatter(p[:, 0], p[:, 1], p[:, 2], s=4, color=colours(m % 10), depthshade=True,
                    label=f"{name}: {np.count_nonzero(sel)} particles")
        section_particles.append((p, r, colours(m % 10)))
    # bodies
    for k, body in enumerate(scene.bodies):
        v, f = np.asarray(body.vertices, float), np.asarray(body.faces, int)
        if not len(f):
            continue
        mesh = Poly3DCollection(v[f], alpha=0.15, facecolor="grey", edgecolor="0.4",
                                linewidths=0.2)
        ax3.add_collection3d(mesh)
        ax2.triplot(v @ e1, v @ e2, f, color="0.5", linewidth=0.3)
        ax3.plot([], [], color="0.5", label=f"body {body.name}: {len(f)} triangles")
    # regions
    for kind, items in (("factory", scene.factories), ("outlet", scene.outlets)):
        for item in items:
            region = getattr(item, "region", None)
            if region is None:
                continue
            for n, line in enumerate(_region_lines(region)):
                label = f"{kind} {item.name}" if n == 0 else None
                ax3.plot(line[:, 0], line[:, 1], line[:, 2], color=_REGION_COLOURS[kind],
                         linewidth=1.0, label=label)
                ax2.plot(line @ e1, line @ e2, color=_REGION_COLOURS[kind], linewidth=1.0)
    # the domain box
    from ..scene.model import Region
    for line in _region_lines(Region(kind="box", box_min=tuple(lo), box_max=tuple(hi))):
        ax3.plot(line[:, 0], line[:, 1], line[:, 2], color="0.8", linewidth=0.6)
    ax3.set_xlim(lo[0], hi[0])
    ax3.set_ylim(lo[1], hi[1])
    ax3.set_zlim(lo[2], hi[2])
    ax3.set_box_aspect(np.maximum(hi - lo, 1e-9 * max(hi - lo)))
    ax3.set_xlabel("x, m")
    ax3.set_ylabel("y, m")
    ax3.set_zlabel("z, m")
    ax3.legend(loc="upper left", fontsize=7)
    # the section spans the domain's projection, so the markers' sizes (scaled to it) hold
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    ax2.set_xlim((corners @ e1).min(), (corners @ e1).max())
    ax2.set_ylim((corners @ e2).min(), (corners @ e2).max())
    ax2.set_aspect("equal")
    ax2.set_title(f"section {section}", fontsize=9)
    ax2.set_xlabel("m")
    ax2.set_ylabel("m")
    def count(n, one, many):
        return f"{n} {one if n == 1 else many}"
    fig.suptitle(f"{Path(scene.source).name} at t = 0: "
                 f"{count(len(placed.radius), 'particle', 'particles')}, "
                 f"{count(len(scene.bodies), 'body', 'bodies')}, "
                 f"{count(len(scene.factories), 'factory', 'factories')}", fontsize=10)
    fig.tight_layout()
    if section_particles:
        # marker diameter = the particle's diameter at the section's scale (points per metre)
        fig.canvas.draw()
        x0, x1 = ax2.get_xlim()
        points_per_metre = ax2.get_window_extent().width * 72.0 / fig.dpi / (x1 - x0)
        for p, r, colour in section_particles:
            ax2.scatter(p @ e1, p @ e2, s=(2.0 * r * points_per_metre) ** 2, color=colour,
                        alpha=0.5, linewidths=0)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


__all__ = ["write_preview"]
