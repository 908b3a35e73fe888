"""What the simulation *holds*: particle state as structure-of-arrays Taichi fields.

Every simulation owns its fields through its own ``ti.FieldsBuilder`` trees, so several
simulations live in one process and ``close()`` frees their memory. Optional per-particle
arrays are allocated only when an enabled effect asks for them (``requests``), so a scene
without plane walls has no wall history, one without EPSD rolling no rolling history.
"""
from __future__ import annotations

import numpy as np
import taichi as ti

from ..setup.memory import bucket
from ..setup.tuning import LIST_GROWTH

VEC = 3
# the moment of inertia of a solid sphere, I = SPHERE_INERTIA m r^2 (2/5)
SPHERE_INERTIA = 0.4


class FieldTree:
    """A set of fields placed in one SNode tree that can be destroyed as a whole."""

    def __init__(self):
        self._builder = ti.FieldsBuilder()
        self._tree = None
        self.fields: dict[str, object] = {}
        # fields whose values mean nothing between kernels (scratch): not checkpointed
        self.scratch: set[str] = set()

    def add(self, name: str, dtype, shape, vector: bool = False, scratch: bool = False):
        f = ti.Vector.field(VEC, dtype) if vector else ti.field(dtype)
        axes = ti.axes(*range(len(shape))) if isinstance(shape, tuple) else ti.i
        self._builder.dense(axes, shape).place(f)
        self.fields[name] = f
        if scratch:
            self.scratch.add(name)
        return f

    def kept(self) -> dict:
        """The fields that hold state (name -> field): all but the scratch ones."""
        return {n: f for n, f in self.fields.items() if n not in self.scratch}

    def finalize(self):
        self._tree = self._builder.finalize()
        return self

    def destroy(self):
        if self._tree is not None:
            self._tree.destroy()
            self._tree = None
        self.fields.clear()


# where a removed particle waits until the next rebuild drops it, m on each axis: far from
# everything, so that it touches nothing (process/outlets.py parks those it removes)
PARKED = 1.0e9


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
    NON_FINITE = 2           # 1.0 when a velocity is NaN or overflowed
    MOVING_COUNT = 3         # moving particles alive
    SIZE = 4


def fit_rows(a: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` rows of ``a``, zero-padded to ``n`` rows: a host copy of an array being
    reallocated with ``n`` entries (pair and mesh-entry arrays that grow)."""
    out = np.zeros((n,) + a.shape[1:], dtype=a.dtype)
    m = min(n, a.shape[0])
    out[:m] = a[:m]
    return out


def grown_capacity(entries: int, alive: int, particle_capacity: int, floor: int = 16,
                   settled_per_particle: float = 0.0) -> int:
    """Room for list entries (pairs, mesh candidates) once ``entries`` no longer fit: 1.5x
    today's (LIST_GROWTH), at least what the particle capacity would need at today's entries per
    particle, and at least ``settled_per_particle`` per alive particle (what the list will hold
    once a loose fill has settled: SETTLED_ENTRIES_PER_PARTICLE). Every reallocation recompiles
    the kernels that read the list (~0.3-1 s of Python-side compilation each time, even from
    the kernel cache; the runs of steps 2-3 s cold), so a scene filling from a factory or a
    bed settling should reallocate a few times, not at every half-again of its entries."""
    per_particle = entries / max(alive, 1)
    # a bucket (engine/values.py): scenes whose lists differ a little share their kernels
    return bucket(int(max(LIST_GROWTH * entries, 1.2 * per_particle * particle_capacity,
                          settled_per_particle * alive, floor)))


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

    # Optional fields are declared by the effects that need them (effects/base.py), e.g. the
    # temperature effect: temperature K, inverse_thermal_mass 1/(J/K) (1/(m (c + X c_w)) when
    # drying, X = moisture kg water per kg dry solid, m the dry mass ``mass``), and in f32
    # scenes temperature_residual (f64): the part of the temperature that f32 cannot hold
    # (engine/precision.py). Code that inserts particles sets them by name.

    # allocated only when the scene has factories or outlets: ``serial`` is the id users see
    # (unique over the whole run), while ``particle_id`` is a slot key < capacity that is
    # re-used after its particle is gone; ``origin`` the factory index (-1: an initial fill),
    # ``birth_time`` s when it was inserted
    PROCESS = {"serial": (False, "int"), "origin": (False, "int"), "birth_time": (False, "real")}

    # sums filled and emptied within one step: zero whenever the state is at a whole step, so
    # a checkpoint written before they existed restores them as zero without a warning
    ZERO_BETWEEN_STEPS = frozenset({"scattered_force", "scattered_torque", "scattered_heat",
                                    "scattered_conductance"})

    def __init__(self, capacity: int, real, n_walls: int, particle_fields: dict,
                 contact_fields: dict, heat: bool = False, process: bool = False):
        """``particle_fields``: {name: (is_vector, kind)} the enabled effects declare;
        ``contact_fields``: the state each contact carries (one per particle and plane wall
        here, named ``wall_<name>``)."""
        self.capacity = capacity
        self.spec = dict(self.CORE, **particle_fields, **(self.PROCESS if process else {}))
        self.process = process
        self.real = real
        self.n_walls = n_walls
        self.tree = FieldTree()
        self.names: list[str] = []
        for name, (vec, kind) in self.spec.items():
            self._add(name, vec, kind)
        self.wall_fields = []
        if n_walls:
            # e.g. the tangential displacement of each particle's contact with each plane wall
            for name in contact_fields:
                self._add_wall("wall_" + name)
                self.wall_fields.append("wall_" + name)
        # scratch for reordering: a shadow per permuted field, so that the reorder moves every
        # field into its shadow in one loop and back in another (engine/broadphase.py). One
        # loop per field instead (a shadow per dtype) made the kernel ~40 loops: each loop is
        # a task that Taichi compiles, and loads from its cache, on its own (~5 ms each warm)
        t = self.tree
        self.shadows = {}
        for name in self.reordered_names():
            f = getattr(self, name)
            self.shadows[name] = t.add("shadow_" + name, f.dtype, tuple(f.shape),
                                       vector=name in self.wall_fields or self.spec[name][0],
                                       scratch=True)
        # force (N) and torque (N m) of the pairs this particle owns, summed by the pair kernel
        self.owned_force = t.add("owned_force", real, capacity, vector=True)
        self.owned_torque = t.add("owned_torque", real, capacity, vector=True)
        if heat:
            # heat flow (W) of the owned pairs; sum of the conductances (W/K) of the last step
            self.owned_heat = t.add("owned_heat", real, capacity)
            self.conductance = t.add("conductance", real, capacity)
        # the serial mode's partner shares (pair_stage.py ``scatter``): the owner adds its partner's
        # force (N), torque (N m), heat (W) and conductance (W/K) here directly - one thread,
        # no race - and the particle stage reads and clears them; zero between steps
        # (ZERO_BETWEEN_STEPS)
        self.scattered_force = t.add("scattered_force", real, capacity, vector=True)
        self.scattered_torque = t.add("scattered_torque", real, capacity, vector=True)
        if heat:
            self.scattered_heat = t.add("scattered_heat", real, capacity)
            self.scattered_conductance = t.add("scattered_conductance", real, capacity)
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

    def reordered_names(self) -> list[str]:
        """The per-particle fields that move together when particles are put back into cell
        order (every declared one and the per-wall ones; not ``reference_position``, which
        the reorder sets from the new positions)."""
        return [n for n in self.spec if n != "reference_position"] + list(self.wall_fields)

    def reorder_pairs(self) -> list[tuple]:
        """(field, its shadow) for each of ``reordered_names``."""
        return [(getattr(self, n), self.shadows[n]) for n in self.reordered_names()]

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

    def __init__(self, capacity: int, real, contact_fields: dict, pair_fields: dict):
        """``contact_fields``: the state each contact carries (the enabled effects declare
        them: tangential_history, rolling_history), kept with a copy of the previous list
        (``old_<name>``) to carry it across rebuilds; ``pair_fields``: the partner's share of
        a pair effect's output (partner_heat W, pair_conductance W/K), valid while touching."""
        self.capacity = capacity
        t = self.tree = FieldTree()
        self.contact_field_names = list(contact_fields)
        self.partner_heat = self.pair_conductance = None
        for name, (vec, kind) in pair_fields.items():
            setattr(self, name, t.add(name, real, capacity, vector=vec))
        self.neighbour = t.add("neighbour", ti.i32, capacity)
        self.mirror = t.add("mirror", ti.i32, capacity)
        # 1 while the pair touches; the partner's force and torque are valid only then, and the
        # history is zero whenever it is 0 (so non-touching pairs cost one byte per step)
        self.contact = t.add("contact", ti.u8, capacity)
        self.partner_force = t.add("partner_force", real, capacity, vector=True)    # N
        self.partner_torque = t.add("partner_torque", real, capacity, vector=True)  # N m
        self.tangential_history = self.rolling_history = None
        self.old_tangential_history = self.old_rolling_history = None
        for name, (vec, kind) in contact_fields.items():
            setattr(self, name, t.add(name, real, capacity, vector=vec))
        # the previous list, by partner id, to carry history across rebuilds
        self.old_partner_id = t.add("old_partner_id", ti.i32, capacity)
        self.old_contact = t.add("old_contact", ti.u8, capacity)
        for name, (vec, kind) in contact_fields.items():
            setattr(self, "old_" + name, t.add("old_" + name, real, capacity, vector=vec))
        t.finalize()

    def destroy(self):
        self.tree.destroy()
