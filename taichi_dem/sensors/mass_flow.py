"""Mass-flow planes (``[[sensors]] kind = "mass_flow"``): the mass and number of particles
crossing a plane (optionally within a radius of its point or inside a box), signed along its
normal.

Device side (:class:`PlaneCrossings`): the drift calls ``count_crossings`` once per moving
particle and step (process/outlets.py composes it into ``after_drift``) and sums the
crossings since the last sample; host side (:class:`MassFlowSensor`): /series
sensors/<name>/mass_flow (kg/s over the output interval) and crossings."""
from __future__ import annotations

import numpy as np
import taichi as ti

from ..engine import transfer


class PlaneCrossings:
    """Fields and the ti.func that count crossings of the scene's mass-flow planes."""

    def __init__(self, scene, tree):
        self.planes = [x for x in scene.sensors if x.kind == "mass_flow"]
        n_planes = max(len(self.planes), 1)
        # mass (kg, signed along the normal) and count of crossings since the last sample
        self.plane_mass = tree.add("plane_mass", ti.f64, n_planes)
        self.plane_count = tree.add("plane_count", ti.i32, n_planes)

    def make_func(self, state, values=None):
        """Compile-time construction of ``count_crossings(i, x_old, x_new)``: x_old and x_new
        are particle i's centre before and after this step's drift (m, unwrapped). With
        ``values`` (engine/values.py) each plane's point, normal, radius and box are read at
        run time (a moved plane compiles nothing); whether it has a radius or a box is
        compiled in."""
        from ..engine.values import reader
        s = state
        planes = []
        for k, x in enumerate(self.planes):
            name = f"mass_flow_{k}"
            has_radius, has_box = x.radius is not None, x.box_min is not None
            planes.append((
                reader(values, name + "_point", tuple(x.point)),
                reader(values, name + "_normal", tuple(x.normal)),
                reader(values, name + "_radius_squared", x.radius ** 2 if has_radius else 0.0),
                reader(values, name + "_box_min", tuple(x.box_min) if has_box else (0.0,) * 3),
                reader(values, name + "_box_max", tuple(x.box_max) if has_box else (0.0,) * 3),
                has_radius, has_box))
        n_planes = len(planes)
        me = self

        @ti.func
        def count_crossings(i, x_old, x_new):
            for k in ti.static(range(n_planes)):
                point, normal = planes[k][0](), planes[k][1]()
                before = (x_old - point).dot(normal)
                after = (x_new - point).dot(normal)
                if (before < 0.0) != (after < 0.0):
                    crossing = x_old + (x_new - x_old) * (before / (before - after))
                    within = True
                    if ti.static(planes[k][5]):
                        off = crossing - point
                        within = off.dot(off) <= planes[k][2]()
                    if ti.static(planes[k][6]):
                        lo, hi = planes[k][3](), planes[k][4]()
                        for a in ti.static(range(3)):
                            if crossing[a] < lo[a] or crossing[a] > hi[a]:
                                within = False
                    if within:
                        sign = 1.0 if after >= 0.0 else -1.0
                        ti.atomic_add(me.plane_mass[k], sign * ti.cast(s.mass[i], ti.f64))
                        ti.atomic_add(me.plane_count[k], 1)

        return count_crossings

    def take(self):
        """(mass kg signed, count) crossed per mass-flow plane since the last call; reset."""
        sums = (self.plane_mass, self.plane_count)
        m, c = transfer.take(sums)              # (one kernel reads and zeroes both)
        return (m[: len(self.planes)].astype(np.float64),
                c[: len(self.planes)].astype(np.int64))


class MassFlowSensor:
    """/series sensors/<name>/mass_flow (kg/s, signed along the normal) and crossings (count)
    over the output interval."""

    def __init__(self, engine):
        self.crossings = engine.process.planes

    def sample(self, values: dict, now) -> None:
        mass, count = self.crossings.take()
        for k, x in enumerate(self.crossings.planes):
            values[f"sensors/{x.name}/mass_flow"] = mass[k] / now.interval if now.interval > 0 else 0.0
            values[f"sensors/{x.name}/crossings"] = float(count[k])
