"""Contact statistics (``[[sensors]] kind = "contact_statistics"``): at every output sample, per
pair kind - particle-particle, particle-wall (the plane walls), particle-body (the meshes) -
the contacts now, their normal force (mean, 90th percentile, largest) and their relative
normal speed (mean, 90th percentile, largest); and the collisions that began since the last
sample with their impact speeds (count, rate, mean, 10th/50th/90th percentile, largest),
counted by the step as each contact begins (the effect the sensor enables writes those):
what EDEM's collision export is read for (the force a flight or a paddle takes, how hard
particles hit each other).
/series sensors/<name>/<kind>/contacts, normal_force_*, normal_speed_*, collisions,
collision_rate, impact_speed_*.

The normal force is Hertz's from each contact's overlap d, F = 4/3 E* sqrt(R*) d^(3/2) (E* of
the material pair, R* = r_i r_j / (r_i + r_j), or r against a wall or a body), the contact
law's elastic part; its damping part, proportional to the normal speed given beside it, is
left out. Particle pairs and walls are found from the positions now (the neighbour list holds
every pair within the skin); body contacts are those the mesh contacts hold from the last
step. Fixed particles (a fill with ``fixed = true``) exert no force on a wall or on each other
and are left out there, as the step leaves them out. Read-only, on the host (numpy), and only
in a scene that asks for it.
"""
from __future__ import annotations

import numpy as np

from ..engine import transfer

KINDS = ("particle", "wall", "body")
_STATISTICS = ("contacts", "normal_force_mean", "normal_force_p90", "normal_force_max",
               "normal_speed_mean", "normal_speed_p90", "normal_speed_max")


def hertz_normal_force(youngs_eff, radius_eff, overlap) -> np.ndarray:
    """F = 4/3 E* sqrt(R*) d^(3/2), N (E* Pa, R* m, d m; zero where d <= 0)."""
    d = np.maximum(np.asarray(overlap, float), 0.0)
    return 4.0 / 3.0 * np.asarray(youngs_eff, float) * np.sqrt(radius_eff) * d ** 1.5


def statistics(force, speed) -> dict:
    """The series of one pair kind from its contacts' normal forces (N) and speeds (m/s)."""
    force, speed = np.asarray(force, float), np.abs(np.asarray(speed, float))
    if not len(force):
        return {"contacts": 0.0, **{k: 0.0 for k in _STATISTICS[1:]}}
    return {"contacts": float(len(force)), "normal_force_mean": float(force.mean()),
            "normal_force_p90": float(np.percentile(force, 90)),
            "normal_force_max": float(force.max()), "normal_speed_mean": float(speed.mean()),
            "normal_speed_p90": float(np.percentile(speed, 90)),
            "normal_speed_max": float(speed.max())}


class ContactStatistics:
    """The contact_statistics sensors of a scene (all read the same contacts)."""

    def __init__(self, scene, engine):
        self.engine = engine
        self.names = [x.name for x in scene.sensors if x.kind == "contact_statistics"]
        tables = engine.model.tables
        self.youngs_eff = np.asarray(tables.youngs_eff, float)
        self.walls = [(np.asarray(w.point, float), np.asarray(w.normal, float),
                       tables.index(w.material)) for w in scene.walls]

    def _particles(self):
        e, s = self.engine, self.engine.state
        n = e.count
        x, v, r, material, alive, inverse_mass = (a[:n] for a in transfer.read(
            [s.position, s.velocity, s.radius, s.material, s.alive, s.inverse_mass]))
        # (a fixed particle: inverse mass 0)
        return (x.astype(float), v.astype(float), r.astype(float), material.astype(int),
                alive != 0, inverse_mass > 0)

    def _pairs(self, x, v, r, material, alive, moving):
        e, s = self.engine, self.engine.state
        n = len(x)
        if e.pairs is None or n == 0:
            return np.zeros(0), np.zeros(0)
        start, owned = (a[:n].astype(np.int64) for a in transfer.read([s.row_start, s.row_owned]))
        neighbour = e.pairs.neighbour.to_numpy()
        i = np.repeat(np.arange(n), owned)
        first = np.repeat(start - np.cumsum(owned) + owned, owned)   # (each row's own start)
        k = first + np.arange(len(i))
        j = neighbour[k].astype(np.int64)
        d = x[i] - x[j]
        grid = e.model.grid
        for a in range(3):
            if grid.periodic[a]:
                d[:, a] -= grid.span[a] * np.round(d[:, a] / grid.span[a])
        distance = np.linalg.norm(d, axis=1)
        overlap = r[i] + r[j] - distance
        touching = ((overlap > 0) & (distance > 0) & alive[i] & alive[j]
                    & (moving[i] | moving[j]))
        i, j, d, distance, overlap = i[touching], j[touching], d[touching], distance[touching], overlap[touching]
        normal = d / distance[:, None]
        radius = r[i] * r[j] / (r[i] + r[j])
        force = hertz_normal_force(self.youngs_eff[material[i], material[j]], radius, overlap)
        speed = np.einsum("ij,ij->i", v[i] - v[j], normal)
        return force, speed

    def _walls(self, x, v, r, material, alive, moving):
        forces, speeds = [np.zeros(0)], [np.zeros(0)]
        for point, normal, wall_material in self.walls:
            distance = (x - point) @ normal
            overlap = r - distance
            touching = (overlap > 0) & alive & moving
            forces.append(hertz_normal_force(self.youngs_eff[material[touching], wall_material],
                                             r[touching], overlap[touching]))
            speeds.append(v[touching] @ normal)
        return np.concatenate(forces), np.concatenate(speeds)

    def _bodies(self, x, v, r, material, alive, moving):
        e = self.engine
        mesh = e.mesh
        n = len(x)
        if mesh is None or n == 0:
            return np.zeros(0), np.zeros(0)
        start, count = (a[:n].astype(np.int64) for a in transfer.read([mesh.mesh_start,
                                                                        mesh.mesh_count]))
        i = np.repeat(np.arange(n), count)
        k = np.repeat(start - np.cumsum(count) + count, count) + np.arange(len(i))
        contact, overlap, normal, point, tri = (a[k] for a in transfer.read(
            [mesh.mesh_contact, mesh.mesh_overlap, mesh.mesh_normal, mesh.mesh_point,
             mesh.mesh_tri]))
        f = mesh.frames
        body_of, body_material, axis_point, offset, spin, velocity = transfer.read(
            [mesh.triangles.tri_body, f.body_material, f.axis_point, f.offset,
             f.angular_velocity, f.body_velocity])
        touching = (contact == 1) & alive[i]
        i, overlap, normal, point = i[touching], overlap[touching].astype(float), \
            normal[touching].astype(float), point[touching].astype(float)
        body = body_of[tri[touching]]
        force = hertz_normal_force(self.youngs_eff[material[i], body_material[body]], r[i],
                                   overlap)
        lever = point - (axis_point[body] + offset[body])
        surface = velocity[body] + np.cross(spin[body], lever)
        speed = np.einsum("ij,ij->i", v[i] - surface, normal)
        return force, speed

    def measure(self) -> dict:
        """{pair kind: its series} of the contacts now."""
        state = self._particles()
        out = {}
        for kind, find in (("particle", self._pairs), ("wall", self._walls),
                           ("body", self._bodies)):
            out[kind] = statistics(*find(*state))
        return out

    def sample(self, values: dict, now) -> None:
        measured = self.measure()
        for name in self.names:
            for kind, series in measured.items():
                for stat, value in series.items():
                    values[f"sensors/{name}/{kind}/{stat}"] = value
