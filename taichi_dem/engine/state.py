"""What the simulation *holds*: particle state as structure-of-arrays Taichi fields.

Every simulation owns its fields through its own ``ti.FieldsBuilder`` trees, so several
simulations live in one process and ``close()`` frees their memory. Optional per-particle
arrays are allocated only when an enabled effect asks for them (``requests``), so a scene
without plane walls has no wall history, one without EPSD rolling no rolling history.
"""
from __future__ import annotations

import numpy as np
import taichi as ti

VEC = 3


class FieldTree:
    """A set of fields placed in one SNode tree that can be destroyed as a whole."""

    def __init__(self):
        self._builder = ti.FieldsBuilder()
        self._tree = None
        self.fields: dict[str, object] = {}

    def add(self, name: str, dtype, shape, vector: bool = False):
        f = ti.Vector.field(VEC, dtype) if vector else ti.field(dtype)
        axes = ti.ij if isinstance(shape, tuple) and len(shape) == 2 else ti.i
        self._builder.dense(axes, shape).place(f)
        self.fields[name] = f
        return f

    def finalize(self):
        self._tree = self._builder.finalize()
        return self

    def destroy(self):
        if self._tree is not None:
            self._tree.destroy()
            self._tree = None
        self.fields.clear()


class Flag:
    """Slots of the engine's ``flags`` field (i32): kernels set them, the host reads them."""
    REBUILD = 0          # 1: rebuild the neighbour lists before the next pair kernel
    LOST = 1             # particles that left the domain since the start (Engine.lost)
    DEAD_IN_SLOTS = 2    # particles removed since the last rebuild, still holding a slot
    SIZE = 3


class Reduction:
    """Slots of the engine's ``reduction`` field (real), filled by Engine.measure's kernel."""
    KINETIC_ENERGY = 0       # J, translational + rotational, of the moving particles
    MAX_SPEED = 1            # m/s
    NON_FINITE = 2           # 1.0 when a velocity or temperature is NaN or overflowed
    MOVING_COUNT = 3         # moving particles alive
    THERMAL_STEP_RATIO = 4   # largest dt sum(h) / (m c) of a particle
    SIZE = 5


class ThermalSum:
    """Slots of the engine's ``thermal_sums`` field (f64: an f32 sum of m c T at 723 K would
    round a heat balance away), filled by Engine.measure's kernel."""
    THERMAL_ENERGY = 0       # sum m c T, J
    THERMAL_MASS = 1         # sum m c, J/K
    WATER_MASS = 2           # kg
    DRY_MASS = 3             # kg of dry solid
    SIZE = 4


def fit_rows(a: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` rows of ``a``, zero-padded to ``n`` rows: a host copy of an array being
    reallocated with ``n`` entries (pair and mesh-entry arrays that grow)."""
    out = np.zeros((n,) + a.shape[1:], dtype=a.dtype)
    m = min(n, a.shape[0])
    out[:m] = a[:m]
    return out


class ParticleState:
    """Per-particle SoA fields, kept in spatial (cell) order; ``particle_id`` maps back to the
    user's order. ``capacity`` slots, of which the first ``count`` are alive after a rebuild.

    Units: position m, velocity m/s, angular_velocity rad/s, acceleration m/s^2,
    angular_acceleration rad/s^2, radius m, mass kg, inverse_mass 1/kg (0 for fixed particles),
    inverse_inertia 1/(kg m^2) (0 for fixed particles).
    """

    # name -> (is_vector, kind) ; kind "real" or "int"
    CORE = {
        "position": (True, "real"), "velocity": (True, "real"),
        "angular_velocity": (True, "real"), "acceleration": (True, "real"),
        "angular_acceleration": (True, "real"), "reference_position": (True, "real"),
        "radius": (False, "real"), "mass": (False, "real"),
        "inverse_mass": (False, "real"), "inverse_inertia": (False, "real"),
        "material": (False, "int"), "particle_id": (False, "int"), "alive": (False, "int"),
    }

    # allocated only when [thermal] is present: temperature K, 1/(m c) 1/(J/K)
    THERMAL = {"temperature": (False, "real"), "inverse_thermal_mass": (False, "real")}
    # allocated only when the scene dries particles (a fill or factory gives ``moisture``):
    # X, kg water per kg dry solid. With it, inverse_thermal_mass is 1/(m (c + X c_w)) (m the
    # dry mass, ``mass``; c_w = [thermal] water_heat_capacity) and changes as the particle
    # dries; code that inserts particles must set both moisture and that thermal mass
    MOISTURE = {"moisture": (False, "real")}

    # allocated only when the scene has factories or outlets: ``serial`` is the id users see
    # (unique over the whole run), while ``particle_id`` is a slot key < capacity that is
    # re-used after its particle is gone; ``origin`` the factory index (-1: an initial fill),
    # ``birth_time`` s when it was inserted
    PROCESS = {"serial": (False, "int"), "origin": (False, "int"), "birth_time": (False, "real")}

    # allocated only for heat in f32 scenes: the part of the temperature (K) and moisture
    # (kg/kg) that f32 cannot hold. The f32 spacing at 723 K is 6.1e-5 K while a cooler's
    # per-step changes are ~1e-6 K: a plain f32 update rounds them away and heat is lost or
    # made. The value is temperature + temperature_residual (compensated summation, f64);
    # fluxes use the f32 part, which is within half a spacing of it
    RESIDUALS = {"temperature_residual": (False, "f64")}
    MOISTURE_RESIDUALS = {"moisture_residual": (False, "f64")}

    def __init__(self, capacity: int, real, n_walls: int, rolling_history: bool,
                 thermal: bool = False, process: bool = False, moisture: bool = False):
        self.capacity = capacity
        # compensated (f64 residual) temperatures only where the mechanics are in f32
        self.compensated = bool(thermal) and real != ti.f64
        self.spec = dict(self.CORE, **(self.THERMAL if thermal else {}),
                         **(self.MOISTURE if moisture else {}),
                         **(self.RESIDUALS if self.compensated else {}),
                         **(self.MOISTURE_RESIDUALS if self.compensated and moisture else {}),
                         **(self.PROCESS if process else {}))
        self.process = process
        self.real = real
        self.n_walls = n_walls
        self.tree = FieldTree()
        self.names: list[str] = []
        for name, (vec, kind) in self.spec.items():
            self._add(name, vec, kind)
        if n_walls:
            # tangential displacement of each particle's contact with each plane wall
            self._add_wall("wall_tangential_history")
            if rolling_history:
                self._add_wall("wall_rolling_history")
        # scratch for reordering: one shadow per dtype/shape
        t = self.tree
        self.shadow_vec = t.add("shadow_vec", real, capacity, vector=True)
        self.shadow_real = t.add("shadow_real", real, capacity)
        self.shadow_int = t.add("shadow_int", ti.i32, capacity)
        self.shadow_f64 = t.add("shadow_f64", ti.f64, capacity) if self.compensated else None
        # force (N) and torque (N m) of the pairs this particle owns, summed by the pair kernel
        self.owned_force = t.add("owned_force", real, capacity, vector=True)
        self.owned_torque = t.add("owned_torque", real, capacity, vector=True)
        if thermal:
            # heat flow (W) of the owned pairs; sum of the conductances (W/K) of the last step
            self.owned_heat = t.add("owned_heat", real, capacity)
            self.conductance = t.add("conductance", real, capacity)
        self.cell = t.add("cell", ti.i32, capacity)
        self.order = t.add("order", ti.i32, capacity)
        self.inverse_order = t.add("inverse_order", ti.i32, capacity)
        self.row_start = t.add("row_start", ti.i32, capacity + 1)
        self.row_count = t.add("row_count", ti.i32, capacity)
        # the first row_owned entries of a row are the pairs this particle owns (computes)
        self.row_owned = t.add("row_owned", ti.i32, capacity)
        # where each particle's neighbour row was before the last reorder (by particle id)
        self.old_row_start_by_id = t.add("old_row_start_by_id", ti.i32, capacity)
        self.old_row_count_by_id = t.add("old_row_count_by_id", ti.i32, capacity)
        t.finalize()

    def _add(self, name, vec, kind):
        dtype = {"real": self.real, "int": ti.i32, "f64": ti.f64}[kind]
        setattr(self, name, self.tree.add(name, dtype, self.capacity, vector=vec))
        self.names.append(name)

    def _add_wall(self, name):
        f = self.tree.add(name, self.real, (self.capacity, self.n_walls), vector=True)
        setattr(self, name, f)
        self.names.append(name)

    def reorder_groups(self):
        """(vector fields, real scalar fields, int fields, per-wall vector fields, f64 scalar
        fields) to permute together when particles are put back into cell order."""
        vec = [getattr(self, n) for n, (v, k) in self.spec.items() if v]
        real = [getattr(self, n) for n, (v, k) in self.spec.items() if not v and k == "real"]
        ints = [getattr(self, n) for n, (v, k) in self.spec.items() if not v and k == "int"]
        walls = [getattr(self, n) for n in ("wall_tangential_history", "wall_rolling_history")
                 if hasattr(self, n)]
        doubles = [getattr(self, n) for n, (v, k) in self.spec.items() if not v and k == "f64"]
        return vec, real, ints, walls, doubles

    def destroy(self):
        self.tree.destroy()


class PairState:
    """Per-neighbour-entry fields of the full (both directions) neighbour list in CSR form.

    Entry k of particle i's row names partner ``neighbour[k]``; a row lists the pairs the
    particle owns first (``row_owned`` of them), then the others. The pair is computed once, by
    its owner (the particle with the smaller ``particle_id``, stable across reorders), which
    sums its own share per particle and stores the partner's force and torque at the entry;
    the partner reads them through ``mirror[k]`` (the owner's entry). The tangential (and EPSD rolling) history lives at the
    owner's entry.
    """

    def __init__(self, capacity: int, real, rolling_history: bool, conduction: bool = False):
        self.capacity = capacity
        t = self.tree = FieldTree()
        # the partner's share of the heat flow (W), valid while touching (conduction only)
        self.partner_heat = t.add("partner_heat", real, capacity) if conduction else None
        self.pair_conductance = t.add("pair_conductance", real, capacity) if conduction else None
        self.neighbour = t.add("neighbour", ti.i32, capacity)
        self.mirror = t.add("mirror", ti.i32, capacity)
        # 1 while the pair touches; the partner's force and torque are valid only then, and the
        # history is zero whenever it is 0 (so non-touching pairs cost one byte per step)
        self.contact = t.add("contact", ti.u8, capacity)
        self.tangential_history = t.add("tangential_history", real, capacity, vector=True)
        self.partner_force = t.add("partner_force", real, capacity, vector=True)    # N
        self.partner_torque = t.add("partner_torque", real, capacity, vector=True)  # N m
        self.rolling_history = (t.add("rolling_history", real, capacity, vector=True)
                                if rolling_history else None)
        # the previous list, by partner id, to carry history across rebuilds
        self.old_partner_id = t.add("old_partner_id", ti.i32, capacity)
        self.old_contact = t.add("old_contact", ti.u8, capacity)
        self.old_tangential_history = t.add("old_tangential_history", real, capacity, vector=True)
        self.old_rolling_history = (t.add("old_rolling_history", real, capacity, vector=True)
                                    if rolling_history else None)
        t.finalize()

    def destroy(self):
        self.tree.destroy()
