"""Divergence: is the state still a physical one? Checked once per output sample (never per
step) by one kernel over the particles; the simulation stops with a message naming the time,
the particle, its position, the likely cause and the fix.

Three criteria (README "Divergence"):

* non-finite position or velocity (NaN or |x| >= 1e30);
* an overlap larger than ``OVERLAP_LIMIT`` = 0.6 of the smaller radius (particle-particle),
  or of the particle's radius (plane walls), or larger than ``BODY_OVERLAP_LIMIT`` = 1.0 of the
  radius with a mesh body (its centre has reached the surface: it is passing through). Hertz
  contacts at the usual softened moduli overlap 0.1-2 % of the radius; a time step too large
  for the stiffness drives overlaps towards a whole radius within a few steps. Between those,
  a kinematic body can pinch particles in a gap narrower than they are (paddle tips and a
  shell): measured 0.53 r with the shell and 0.41 r between particles in
  tests/regression/test_hard_cases.py - not a numerical fault, so it is warned about
  ("pinched", simulation.py) rather than stopped. Pairs of two fixed particles are not
  checked (they exert no forces);
* a speed above ``SPEED_FACTOR`` = 10 times the expected largest speed the time step was
  chosen for (timestep.expected_max_speed: free fall across the domain, the initial speeds
  and the fastest body surface) - 100 times the kinetic energy any source in the scene can
  give a particle.

Both limits are attributes of ``sim.divergence`` and may be changed from Python.
"""

import time as _time

import numpy as np
import taichi as ti

from ..engine import transfer
from ..errors import DivergenceError

OVERLAP_LIMIT = 0.6          # of the smaller radius
BODY_OVERLAP_LIMIT = 1.0     # of the radius: the centre reaches a body's surface
SPEED_FACTOR = 10.0          # times the expected largest speed (m/s)
_NONE = 2 ** 30              # "no particle" in the index reductions


class DivergenceGuard:
    """The per-sample check of one simulation (``sim.divergence``): one of its ``checks``,
    called as ``guard(measured)`` before the sample's series are taken."""

    def __init__(self, sim):
        self.sim = sim
        e = sim.engine
        self.overlap_limit = OVERLAP_LIMIT
        self.expected_speed = float(sim.timestep.expected_speed)
        self.speed_limit = SPEED_FACTOR * self.expected_speed
        t = e.new_tree()
        self.worst = t.add("divergence_worst_overlap", e.real, e.state.capacity)
        self.index = t.add("divergence_index", ti.i32, 3)     # [non-finite, overlap, speed]
        self.largest = t.add("divergence_largest", e.real, 2)  # [overlap ratio, speed m/s]
        t.finalize()
        self._key = None
        self.seconds = 0.0          # wall time spent checking (measured for BENCHMARKS.md)
        self.checks = 0

    def _compile(self):
        e = self.sim.engine
        s, p, mesh = e.state, e.pairs, e.mesh
        worst, index, largest = self.worst, self.index, self.largest
        minimum_image = e.minimum_image
        walls = [(tuple(w.point), tuple(w.normal)) for w in e.walls]
        n_walls = len(walls)
        has_mesh = mesh is not None
        body_scale = OVERLAP_LIMIT / BODY_OVERLAP_LIMIT

        @ti.kernel
        def scan(n: ti.i32, serial_loops: ti.template()):
            largest[0] = 0.0
            largest[1] = 0.0
            for k in ti.static(range(3)):
                index[k] = _NONE
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                worst[i] = 0.0
                if s.alive[i] != 0:
                    x, v = s.position[i], s.velocity[i]
                    finite = True
                    for k in ti.static(range(3)):
                        if not (ti.abs(x[k]) < 1e30 and ti.abs(v[k]) < 1e30):
                            finite = False
                    if not finite:
                        ti.atomic_min(index[0], i)
                    else:
                        ri = s.radius[i]
                        movable = s.inverse_mass[i] > 0.0
                        ratio = 0.0
                        for k in range(s.row_start[i], s.row_start[i] + s.row_owned[i]):
                            j = p.neighbour[k]
                            if movable or s.inverse_mass[j] > 0.0:
                                d = minimum_image(x - s.position[j])
                                overlap = ri + s.radius[j] - d.norm()
                                if overlap > 0.0:
                                    ratio = ti.max(ratio, overlap / ti.min(ri, s.radius[j]))
                        if movable:
                            for w in ti.static(range(n_walls)):
                                overlap = ri - (x - ti.Vector(walls[w][0])).dot(ti.Vector(walls[w][1]))
                                if overlap > 0.0:
                                    ratio = ti.max(ratio, overlap / ri)
                            if ti.static(has_mesh):
                                for k in range(mesh.mesh_start[i], mesh.mesh_start[i] + mesh.mesh_count[i]):
                                    if mesh.mesh_contact[k] != 0:
                                        # measured against the body limit, expressed on the
                                        # particle scale of overlap_limit
                                        ratio = ti.max(ratio, mesh.mesh_overlap[k] / ri
                                                       * body_scale)
                        worst[i] = ratio
                        ti.atomic_max(largest[0], ratio)
                        ti.atomic_max(largest[1], v.norm())
            # which particle: the first (lowest slot) holding the largest value
            ti.loop_config(serialize=serial_loops)
            for i in range(n):
                if s.alive[i] != 0:
                    if largest[0] > 0.0 and worst[i] >= largest[0]:
                        ti.atomic_min(index[1], i)
                    speed = s.velocity[i].norm()
                    if largest[1] > 0.0 and speed >= largest[1]:
                        ti.atomic_min(index[2], i)

        self._scan = e.serial_switch(scan)

    def __call__(self, measured: dict) -> None:
        self.check(self.sim.time)

    def check(self, time: float) -> None:
        """Raise DivergenceError when the state at ``time`` is no longer physical."""
        t0 = _time.perf_counter()
        e = self.sim.engine
        key = (e.pairs, getattr(e.mesh, "entries_tree", None))
        # the kernel captured the pair and mesh entry arrays: recompile when they were
        # reallocated (compared by identity; holding them keeps an id from being reused)
        if self._key is None or any(a is not b for a, b in zip(key, self._key)):
            self._compile()
            self._key = key
        self._scan(e.count)
        idx, big = transfer.read([self.index, self.largest])
        big = big.astype(np.float64)
        self.seconds += _time.perf_counter() - t0
        self.checks += 1
        if idx[0] != _NONE:
            raise DivergenceError(self._describe(
                time, int(idx[0]), "has a non-finite position or velocity",
                "a time step too large for the stiffest contact (the explicit integration blew "
                "up)", "reduce simulation.dt or rayleigh_fraction (dt = \"auto\" uses 0.2 x the "
                "Rayleigh time); if the scene has very stiff walls or bodies, check their "
                "materials' youngs_modulus"))
        if big[0] > self.overlap_limit and idx[1] != _NONE:
            raise DivergenceError(self._describe(
                time, int(idx[1]),
                f"overlaps a neighbour (particle, wall or body) by {big[0]:.3g} of the smaller "
                f"radius (limit {self.overlap_limit:g}; a body's overlap counts as "
                f"{OVERLAP_LIMIT / BODY_OVERLAP_LIMIT:g} x its share of the radius)",
                "contacts far too soft for the load or the impact speed (youngs_modulus too "
                "low), particles created overlapping, or a body pushing particles into a wall",
                "raise youngs_modulus (softened moduli below ~1e6 Pa let a deep bed sink into "
                "itself), check the fills and factory regions, or slow the bodies"))
        if big[1] > self.speed_limit and idx[2] != _NONE:
            raise DivergenceError(self._describe(
                time, int(idx[2]),
                f"moves at {big[1]:.4g} m/s, more than {self.speed_limit / self.expected_speed:g} "
                f"x the {self.expected_speed:.3g} m/s expected (free fall across the domain, "
                f"initial and body surface speeds)",
                "a time step too large for the stiffest contact, or two particles created "
                "deeply overlapping (their repulsion launches them)",
                "reduce simulation.dt or rayleigh_fraction, and check the fills and factory "
                "regions for overlaps"))

    def _describe(self, time, slot, what, cause, fix) -> str:
        s = self.sim.engine.state
        pid = int(s.particle_id[slot])
        x = [float(s.position[slot][k]) for k in range(3)]
        return (f"the simulation diverged at t = {time:.6g} s: particle {pid} at "
                f"({x[0]:.4g}, {x[1]:.4g}, {x[2]:.4g}) m {what}. Likely cause: {cause}. "
                f"Fix: {fix}.")
