"""Prescribed motion of rigid triangle-mesh bodies, host side (plain numpy, no Taichi).

:class:`BodyKinematics` knows each body's rotation angle and offset at any time from its speed
schedule, and bounds how far any vertex has moved since the triangles were last binned;
``triangle_arrays`` gives the reference triangles (their vertices at t = 0) that the device
side (mesh_contacts.py) rotates into place each step.
"""

import math

import numpy as np

from taichi_dem.geometry.mesh import rotation_matrix

MAX_SCHEDULE = 64      # speed schedule points per body on the device


class BodyKinematics:
    """Angles and offsets of every body over time (host side, float64)."""

    def __init__(self, bodies):
        self.bodies = bodies
        self.names = [b.name for b in bodies]
        # schedule rows: (start time s, speed rad/s, angle at start rad)
        self.schedules: list[list[tuple[float, float, float]]] = []
        self.reach = np.zeros(len(bodies))
        for k, b in enumerate(bodies):
            rows = []
            angle = 0.0
            points = b.motion.speed.points if b.motion.speed else ((0.0, 0.0),)
            for n, (t, w) in enumerate(points):
                if n:
                    t_prev, w_prev, a_prev = rows[-1]
                    angle = a_prev + w_prev * (t - t_prev)
                rows.append((float(t), float(w), angle))
            self.schedules.append(rows)
            axis_point = np.asarray(b.motion.axis_point, float)
            axis = np.asarray(b.motion.axis_direction, float)
            rel = b.vertices - axis_point
            radial = rel - np.outer(rel @ axis, axis)
            self.reach[k] = float(np.max(np.linalg.norm(radial, axis=1))) if len(rel) else 0.0

    def speed(self, k: int, time: float) -> float:
        """Angular speed of body k at ``time``, rad/s."""
        w = self.schedules[k][0][1]
        for t, speed, _ in self.schedules[k]:
            if time >= t:
                w = speed
        return w

    def angle(self, k: int, time: float) -> float:
        """Rotation angle of body k at ``time``, rad."""
        row = self.schedules[k][0]
        for r in self.schedules[k]:
            if time >= r[0]:
                row = r
        return row[2] + row[1] * (time - row[0])

    def pose(self, k: int, time: float) -> tuple[np.ndarray, np.ndarray]:
        """(R, T) of body k at ``time``: a vertex given at x0 in the scene is at R x0 + T (R a
        3x3 rotation, T in m): the turn by its angle about its axis, then its translation."""
        m = self.bodies[k].motion
        axis = np.asarray(m.axis_direction, float)
        point = np.asarray(m.axis_point, float)
        rot = rotation_matrix(axis, self.angle(k, time))
        return rot, point - rot @ point + np.asarray(m.velocity, float) * time

    def set_speed(self, k: int, time: float, speed: float):
        """From ``time`` on, body k turns at ``speed`` rad/s (later scheduled points dropped)."""
        rows = [r for r in self.schedules[k] if r[0] < time]
        rows.append((time, float(speed), self.angle(k, time)))
        if len(rows) > MAX_SCHEDULE:
            rows = rows[-MAX_SCHEDULE:]
        self.schedules[k] = rows

    def surface_speed(self, k: int, time: float) -> float:
        """Largest speed of any point of body k at ``time``, m/s."""
        v = np.linalg.norm(self.bodies[k].motion.velocity)
        return abs(self.speed(k, time)) * self.reach[k] + float(v)

    def max_surface_speed(self) -> float:
        """Largest surface speed of any body over its whole schedule, m/s."""
        best = 0.0
        for k, rows in enumerate(self.schedules):
            w = max(abs(r[1]) for r in rows)
            best = max(best, w * self.reach[k] + float(np.linalg.norm(self.bodies[k].motion.velocity)))
        return best

    def displacement(self, k: int, t0: float, t1: float) -> float:
        """Upper bound of how far any vertex of body k moved between t0 and t1, m."""
        turned = abs(self.angle(k, t1) - self.angle(k, t0))
        chord = 2.0 * self.reach[k] * math.sin(min(turned, math.pi) / 2.0)
        return chord + float(np.linalg.norm(self.bodies[k].motion.velocity)) * abs(t1 - t0)

    def schedule_arrays(self):  # noqa: D102
        """(time, speed, angle, count) arrays of shape (B, MAX_SCHEDULE) for the device."""
        b = max(len(self.bodies), 1)
        times = np.zeros((b, MAX_SCHEDULE))
        speeds = np.zeros((b, MAX_SCHEDULE))
        angles = np.zeros((b, MAX_SCHEDULE))
        counts = np.zeros(b, np.int32)
        for k, rows in enumerate(self.schedules):
            counts[k] = len(rows)
            for n, (t, w, a) in enumerate(rows):
                times[k, n], speeds[k, n], angles[k, n] = t, w, a
        return times, speeds, angles, counts


def triangle_arrays(bodies):
    """Reference triangles of all bodies: (T, 3, 3) vertices at t = 0 and (T,) body index."""
    tris, owner = [], []
    for k, b in enumerate(bodies):
        tris.append(b.vertices[b.faces])
        owner.append(np.full(len(b.faces), k, np.int32))
    if not tris:
        return np.zeros((0, 3, 3)), np.zeros(0, np.int32)
    return np.concatenate(tris), np.concatenate(owner)
