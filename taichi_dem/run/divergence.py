"""Divergence: is the state still a physical one? Checked once per output sample (never per
step) by one kernel over the particles; the simulation stops with a message naming the time,
the particle, its position, the likely cause and the fix.

Three criteria (README "Divergence"):

* a non-finite state (NaN or |x| >= 1e30): position, velocity, angular velocity and, where
  the scene has them, temperature (also one not above 0 K) and moisture. The message names
  the quantity and the cause that fits it (``non_finite_message``): a non-finite velocity is
  the explicit integration blowing up (a time step too large); a non-finite position beside
  a finite velocity cannot come from a step (it moves a particle by dt x its velocity) and was
  put into the state; a non-finite temperature is an unstable or overflowing heat balance;
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

import math
import time as _time
from typing import Optional

import numpy as np
import taichi as ti

from ..engine import transfer
from ..errors import DivergenceError

OVERLAP_LIMIT = 0.6          # of the smaller radius
BODY_OVERLAP_LIMIT = 1.0     # of the radius: the centre reaches a body's surface
SPEED_FACTOR = 10.0          # times the expected largest speed (m/s)
_NONE = 2 ** 30              # "no particle" in the index reductions
# the state a particle must hold finite, in the order a message blames them, with units
_QUANTITIES = {"velocity": "m/s", "angular_velocity": "rad/s", "position": "m",
               "temperature": "K", "moisture": "kg/kg"}


def _value(field, slot: int) -> np.ndarray:
    """One particle's value of a state field (a vector or a scalar) as a float array."""
    v = field[slot]
    return np.atleast_1d(np.asarray(v.to_numpy() if hasattr(v, "to_numpy") else v, dtype=float))


def _wrong(quantity: str, values: np.ndarray) -> np.ndarray:
    """Per row of ``values``: not a physical ``quantity`` (non-finite or |x| >= 1e30; a
    temperature also at or below 0 K), as the scan kernel tests it."""
    v = np.asarray(values, dtype=np.float64)
    bad = ~(np.abs(v) < 1e30)
    if quantity == "temperature":
        bad |= ~(v > 0.0)
    return bad.reshape(len(v), -1).any(axis=1) if v.ndim > 1 else bad


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
        self.worst = t.add("divergence_worst_overlap", e.model.real, e.state.capacity)
        self.index = t.add("divergence_index", ti.i32, 3)     # [non-finite, overlap, speed]
        self.largest = t.add("divergence_largest", e.model.real, 2)  # [overlap ratio, speed m/s]
        t.finalize()
        self._key = None
        self.seconds = 0.0          # wall time spent checking (measured for BENCHMARKS.md)
        self.checks = 0

    def _compile(self):
        e = self.sim.engine
        s, p, mesh = e.state, e.pairs, e.mesh
        worst, index, largest = self.worst, self.index, self.largest
        minimum_image = e.minimum_image
        walls = [(tuple(w.point), tuple(w.normal)) for w in e.model.scene.walls]
        n_walls = len(walls)
        has_mesh = mesh is not None
        body_scale = OVERLAP_LIMIT / BODY_OVERLAP_LIMIT
        has_temperature = "temperature" in s.spec
        has_moisture = "moisture" in s.spec

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
                    x, v, w = s.position[i], s.velocity[i], s.angular_velocity[i]
                    finite = True
                    for k in ti.static(range(3)):
                        if not (ti.abs(x[k]) < 1e30 and ti.abs(v[k]) < 1e30
                                and ti.abs(w[k]) < 1e30):
                            finite = False
                    if ti.static(has_temperature):
                        if not (s.temperature[i] > 0.0 and s.temperature[i] < 1e30):
                            finite = False
                    if ti.static(has_moisture):
                        if not ti.abs(s.moisture[i]) < 1e30:
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
        self.check(self.sim.time, measured)

    def check(self, time: float, measured: Optional[dict] = None) -> None:
        """Raise DivergenceError when the state at ``time`` is no longer physical
        (``measured``: the sample's sums, engine/measure.py, for the thermal step ratio)."""
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
            raise DivergenceError(self.non_finite_message(time, int(idx[0]), measured))
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
                "deeply overlapping (their repulsion launches them)" + self._rolling_cause(),
                "reduce simulation.dt or rayleigh_fraction, and check the fills and factory "
                "regions for overlaps" + self._rolling_fix()))

    def non_finite_message(self, time: float, slot: Optional[int] = None,
                           measured: Optional[dict] = None) -> str:
        """The divergence message for a non-finite (or, for a temperature, not positive)
        quantity of the particle in ``slot`` at ``time`` s (None: the first such particle,
        found on the host - the rare path after Measure flagged the sample): which quantity,
        its value and the cause that fits that quantity."""
        s = self.sim.engine.state
        n = self.sim.engine.count
        names = [q for q in _QUANTITIES if q in s.spec]
        if slot is None:
            arrays = {q: getattr(s, q).to_numpy()[:n] for q in names}
            bad = np.zeros(n, dtype=bool)
            for q in names:
                bad |= _wrong(q, arrays[q])
            bad &= s.alive.to_numpy()[:n] != 0
            rows = np.nonzero(bad)[0]
            if not len(rows):       # the flag was a sum's overflow: the largest speed names it
                speed = np.linalg.norm(arrays["velocity"], axis=1)
                rows = [int(np.argmax(np.where(s.alive.to_numpy()[:n] != 0, speed, -1.0)))]
            slot = int(rows[0])
        values = {q: _value(getattr(s, q), slot) for q in names}
        # the first wrong in _QUANTITIES' order: a velocity before the position it moves
        quantity = next((q for q in names if np.any(_wrong(q, values[q]))), "velocity")
        shown = ", ".join(f"{v:.4g}" for v in values[quantity])
        unit = _QUANTITIES[quantity]
        if quantity == "temperature" and np.all(np.isfinite(values[quantity])):
            what = f"has a temperature of {shown} K, not above absolute zero"
        else:
            what = (f"has a non-finite {quantity.replace('_', ' ')} "
                    f"({'[' + shown + ']' if len(values[quantity]) > 1 else shown} {unit})")
        cause, fix = self._cause(quantity, measured)
        return self._describe(time, slot, what, cause, fix)

    def _cause(self, quantity: str, measured: Optional[dict]) -> tuple[str, str]:
        """(likely cause, fix) of a non-finite ``quantity``."""
        if quantity in ("velocity", "angular_velocity"):
            return ("a time step too large for the stiffest contact (the explicit integration "
                    "blew up)" + self._rolling_cause(),
                    "reduce simulation.dt or rayleigh_fraction (dt = \"auto\" uses "
                    "0.2 x the Rayleigh time); if the scene has very stiff walls or bodies, check "
                    "their materials' youngs_modulus" + self._rolling_fix())
        if quantity == "position":
            return ("not the integration: a step moves a particle by dt x its velocity, which is "
                    "finite, so the position was put into the state non-finite (written from "
                    "Python between steps, or an initial state that was not checked)",
                    "check what sets the particles' positions (sim.engine.state, an edited "
                    "checkpoint); a scene's fills and start files are checked on load")
        ratio = (measured or {}).get("thermal_step_ratio")
        if quantity == "temperature":
            if ratio is not None and not math.isfinite(ratio):
                return ("the heat balance overflowed (dt sum(h)/(m c) is not finite): "
                        "temperatures, conductivities or heat capacities so extreme that a heat "
                        "flow or conductance is beyond the floating-point range (radiation's "
                        "grows as T^3 - T^4)",
                        "check the temperatures of the fills, factories, walls, bodies and gas "
                        "and the materials' thermal_conductivity, heat_capacity and emissivity "
                        "for wrong units")
            if ratio is not None and ratio >= 1.0:
                return (f"the temperature update is unstable: dt sum(h)/(m c) = {ratio:.3g} >= 1 "
                        "(dt the thermal step, thermal.time_scale x simulation.dt)",
                        f"reduce simulation.dt or thermal.time_scale (by {ratio:.2g}x at least), "
                        "or raise heat_capacity/lower thermal_conductivity if they are scaled")
            return ("heat flows too large for the particle's heat capacity: an unstable "
                    "temperature update (thermal.time_scale x simulation.dt too long), or "
                    "temperatures, conductivities or heat capacities so extreme that the heat "
                    "balance overflows (radiation grows as T^4)",
                    "check the materials' heat_capacity and thermal_conductivity and the "
                    "temperatures of the fills, factories, walls, bodies and gas; reduce "
                    "thermal.time_scale or simulation.dt")
        return ("an unstable drying update: evaporation faster than the step can follow "
                "(thermal.time_scale x simulation.dt too long), or absurd moistures or gas "
                "conditions", "check the fills' and factories' moisture and the [thermal] "
                "drying and gas keys; reduce thermal.time_scale or simulation.dt")

    def _constant_torque_rolling(self) -> bool:
        """Whether an interaction of the scene uses the constant-torque rolling model."""
        return any(i.rolling_friction > 0.0 and i.rolling_model == "constant_torque"
                   for i in self.sim.scene.interactions.values())

    def _rolling_cause(self) -> str:
        """The constant-torque rolling model's known divergence, when the scene uses it
        (docs/explanation/01_contacts_and_engine.md, "Known limits"): its spin limiter acts
        per contact, so a sphere with three or more contacts on the same spin has it reversed
        and amplified each step up to the mu_r R* F_n cap; at high sliding and rolling
        friction under a heavy load that growth runs away, and no time step cures it."""
        if not self._constant_torque_rolling():
            return ""
        return ("; or the constant-torque rolling model at high friction: its spin limiter "
                "acts per contact, so a sphere in a pocket of three or more contacts has its "
                "spin reversed and amplified each step (a smaller dt does not cure this)")

    def _rolling_fix(self) -> str:
        if not self._constant_torque_rolling():
            return ""
        return ("; where the constant-torque model diverges, set model = \"epsd\" in the "
                "[[interactions]] entry (a rolling spring that holds a static torque without "
                "the chatter) and calibrate it again")

    def _describe(self, time, slot, what, cause, fix) -> str:
        s = self.sim.engine.state
        pid = int(s.particle_id[slot])
        x = [float(s.position[slot][k]) for k in range(3)]
        return (f"the simulation diverged at t = {time:.6g} s: particle {pid} at "
                f"({x[0]:.4g}, {x[1]:.4g}, {x[2]:.4g}) m {what}. Likely cause: {cause}. "
                f"Fix: {fix}.")
