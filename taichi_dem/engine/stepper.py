"""What *advances* the simulation: the step, composed only of the effects the scene enables.

One step (velocity Verlet):
  drift:  v += a dt/2, w += alpha dt/2, x += v dt; wrap periodic faces; mark particles that
          left the domain; flag a rebuild if any moved more than half the skin
  rebuild neighbours when flagged (broadphase.py)
  pair:   one kernel over owned neighbour entries: the contact geometry once
          (contacts/geometry.py), then the contact law (contacts/law.py), the enabled contact
          effects unrolled on it; the owner sums its own share, the partner's share is stored
          at the entry - no atomics (serial mode: added to the partner's sums directly; the
          worker threads: added to the partner's sums in the worker's own copy)
  cell:   effects with a per-cell stage (the plug-flow gas marching cell by cell)
  gather: each particle adds its partners' shares through the mirror index (in the serial
          mode the owners have added them to its scattered_* sums already; on the workers
          it adds its sums of each copy in order), runs the same
          contact law on its plane walls and mesh triangles, then the particle effects
          (gravity, convection, gas, radiation), the integrate stage (temperature, drying) and
          the second half kick v += a dt/2; within a run of steps it goes on with the next
          step's drift (one pass over the particles less)
The effects (effects/, thermal/effects.py) declare their stage, fields and tables; those not
enabled are neither allocated nor compiled (``ti.static``). The engine never imports thermal/.

The step exists once, as the ti.funcs ``drift_particle``, ``pair_particle``,
``gather_particle`` and ``begin_step``; its drivers (drivers.py) run them one launch per stage,
as runs of steps on one thread (the serial mode, below ``parallel_from`` particles), or as runs
on the persistent worker threads (workers.py). The modes add a particle's partners' shares in
different orders - the same physics to round-off; each is deterministic (the workers' for a
given number of threads). The model the engine is built from is model.py; the particles are
created by insertion.py; the neighbour lists are broadphase.py's; the sums at a sample are
measure.py's.
"""

from dataclasses import dataclass
from typing import Callable

import numpy as np
import taichi as ti

from . import backend, transfer
from .broadphase import Broadphase
from .model import Model
from .insertion import Insertion
from .measure import Measure
from ..contacts.geometry import contact_types, make_geometry
from ..contacts.history import history_members, make_history_io
from ..contacts.law import make_contact_law, margin_fraction
from ..contacts.planes import PlaneWalls, make_plane_contacts
from ..effects.base import EffectContext
from .state import FieldTree, Flag, PairState, ParticleState, Reduction, fit_rows
from . import drivers
from ..setup import tuning
from ..setup.tuning import PARALLEL_FROM
from .drift import make_drift
from .holding import Holding
from .gather_stage import GatherStage
from .pair_stage import PairStage, make_conducted_of
from .values import RuntimeValues
from .workers import WorkerPool, persistent_workers


@dataclass(frozen=True)
class EngineParts:
    """What the layers above the engine supply to it, so that it imports none of them
    (docs/architecture.md "Layers"): the bodies' host motion (``kinematics``, a
    bodies/kinematics.py BodyKinematics, or None) and the factories of the mesh contacts
    (``mesh(engine, kinematics)``: bodies/mesh_contacts.py) and of the process device
    (``process(engine, tree)``: process/outlets.py). run/simulation.py ``engine_parts``
    makes them for a scene."""
    kinematics: object = None
    mesh: "Callable | None" = None
    process: "Callable | None" = None


class Engine:
    """Owns the device state of one simulation and the kernels that advance it."""

    def __init__(self, model: Model, parallel_from: "int | None" = None,
                 parts: "EngineParts | None" = None):
        """``model``: what the simulation is (model.py, frozen); ``parallel_from``: particles
        from which a CPU runs the step's loops on all threads; ``parts``: the bodies' and the
        process's parts, which a scene with bodies, factories, outlets or flow sensors needs."""
        parts = parts if parts is not None else EngineParts()
        self.model = model
        scene = model.scene
        tables = model.tables
        real = model.real
        capacity = model.capacity
        # the loop mode of every kernel (serial_switch); updated with the particle count
        self.threads = backend.cpu_threads()
        self.parallel_from = PARALLEL_FROM if parallel_from is None else int(parallel_from)
        self.serial = False
        self.choose_loop_mode(0)

        # several steps per launch in the serial mode (drivers.run_steps), unless some
        # effect's cell stage has no ti.func form
        self.runs = self.threads is not None and all(hasattr(e, "cell_func")
                                                     for e in self.model.cell_effects)
        self.trees: list[FieldTree] = []
        # scene values the kernels read at run time (values.py): made first, so their place
        # is the same in every simulation; the grid's layout and the skin are read from them
        self.values = RuntimeValues(self.new_tree(), real)
        self.model.grid.bind(self.values)
        self.skin_of = self.values.scalar("skin", self.model.skin)
        # runs of steps on every thread above parallel_from (persistent_workers; off again,
        # for good, if its barrier waits show the threads sharing the cores with other work)
        self.worker_pool = WorkerPool(persistent_workers(self.threads) if self.runs else 0,
                                      capacity, real, self.model.heat,
                                      copies=tuning.WORKER_COPIES)
        has_planes = any(x.kind == "mass_flow" for x in scene.sensors)
        self.state = ParticleState(capacity, real, len(scene.walls), model.particle_fields,
                                   self.model.contact_fields, heat=self.model.heat,
                                   process=bool(scene.factories or scene.outlets))
        self.trees.append(self.state.tree)
        t = self.new_tree()
        m = len(tables.names)
        # the material-pair tables the enabled effects read, under their physics names
        self.table = {name: t.add(name, ti.i32 if values.dtype.kind in "iu" else real, (m, m))
                      for name, values in model.table_values.items()}
        # named slots: Flag (engine/state.py)
        self.flags = t.add("flags", ti.i32, Flag.SIZE)
        self.wall_force = t.add("wall_force", real, max(len(scene.walls), 1), vector=True)
        # the plane walls as fields, read in a loop (contacts/planes.py)
        self.plane_walls = PlaneWalls(scene.walls, tables.index, model.heats_walls,
                                      real, t)
        self.reduction = t.add("reduction", real, Reduction.SIZE)   # named slots: Reduction
        if self.model.heat:
            self.wall_heat = t.add("wall_heat", real, max(len(scene.walls), 1))
        # what the effects see: the model, the values, the tables and the state, read-only
        self.context = EffectContext(model, self.values, self.table, self.state, self)
        for e in self.model.effect_list:
            e.allocate(self.context, t)
        self.process = None
        if scene.factories or scene.outlets or has_planes:
            if parts.process is None:
                raise ValueError("a scene with factories, outlets or flow sensors needs "
                                 "EngineParts.process (run/simulation.py engine_parts)")
            self.process = parts.process(self, t)
        t.finalize()
        self.removed_batches: list = []    # removal-log entries drained at rebuilds
        self.before_rebuild = None         # host hook (engine) before a rebuild in advance
        # the serial mode rebuilds in one launch (Broadphase.fused_rebuild); False: the
        # separate kernels (tests compare the two)
        self.fused_rebuilds = True
        # the parallel mode on the workers rebuilds on them in one launch
        # (Broadphase.rebuild_on_workers); False: the separate kernels (tests compare the two)
        self.rebuilds_on_workers = True
        npf = np.float64 if real == ti.f64 else np.float32
        # the tables, the walls and what the effects allocated: one copy kernel for them all
        transfer.write([(self.table[name], values.astype(np.int32 if values.dtype.kind in "iu"
                                                        else npf))
                        for name, values in model.table_values.items()]
                       + self.plane_walls.writes()
                       + [w for e in self.model.effect_list for w in (e.upload(self.context) or [])])
        self.time = 0.0
        self.pairs: "PairState | None" = None
        self.broadphase = Broadphase(self)
        self.context.attach("broadphase", self.broadphase)
        self.mesh = None
        # the bodies' motion on the host (kinematics.py), and their contacts on the device
        self.kinematics = parts.kinematics
        if scene.bodies:
            if parts.mesh is None or parts.kinematics is None:
                raise ValueError("a scene with bodies needs EngineParts.kinematics and .mesh "
                                 "(run/simulation.py engine_parts)")
            self.mesh = parts.mesh(self, self.kinematics)
            self.context.attach("mesh", self.mesh)
        for x in self.model.effect_list:
            x.prepare(self.context)         # (what needs the broadphase and the mesh)
        self.holding = Holding(self.model.effect_list, self.context)
        # the steps it compiles, by whether they read the holder's hooks (engine/holding.py):
        # holds? -> {"holding", "drift": (drift_particle, drift), "pairs": the pair kernels}
        self._variants = {False: {"holding": self.holding}}
        if self.holding.any:
            # the step while the holder holds nothing: the hooks' constants
            self._variants = {True: {"holding": self.holding},
                              False: {"holding": Holding(self.model.effect_list,
                                                         self.context, idle=True)}}
        self._compile_particle_kernels()
        self.count = 0                     # slots in use
        self._measure = None               # (measure.py, compiled on first use)
        self.insertion = Insertion(self)

    @property
    def workers(self) -> int:
        """The persistent worker threads the runs of steps use now (0: none, or they gave
        way; workers.WorkerPool)."""
        return self.worker_pool.workers

    @workers.setter
    def workers(self, count: int):
        self.worker_pool.workers = count      # (0: the parallel kernels from now on)

    def choose_loop_mode(self, n: int) -> bool:
        """Serial loops for ``n`` particles? On a GPU never; on one CPU thread always; else
        below ``parallel_from`` particles, with a band of +-20 % so that a count wandering
        around it does not switch (each mode compiles its own kernels, once)."""
        if self.threads is None:
            serial = False
        elif self.threads == 1:
            serial = True
        elif self.serial:
            serial = n < 1.2 * self.parallel_from
        else:
            serial = n < 0.8 * self.parallel_from
        self.serial = serial
        return serial

    def serial_switch(self, kernel):
        """``kernel`` called with the engine's loop mode (``serial``) as its last argument, a
        ti.template(): its loops run on one thread when it is True (``ti.loop_config``)."""
        def launch(*args):
            return kernel(*args, self.serial)
        launch.kernel = kernel
        return launch

    def new_tree(self) -> FieldTree:
        t = FieldTree()
        self.trees.append(t)
        return t

    def recompile_pair_kernels(self):
        """New kernel objects after arrays they use were reallocated (compiled on first use)."""
        self._compile_pair_kernels(self.pairs)

    def grow_pairs(self, capacity: int):
        """(Re)allocate the pair arrays with room for ``capacity`` entries, keeping the saved
        previous list (old_* arrays) so the history can still be carried."""
        old = self.pairs
        new = PairState(capacity, self.model.real, self.model.contact_fields, self.model.pair_fields)
        if old is not None:
            # the partner ids and every history value the enabled effects keep, by name
            names = ["old_partner_id"] + ["old_" + name for name in self.model.contact_fields]
            saved = transfer.read([getattr(old, name) for name in names])
            transfer.write([(getattr(new, name), fit_rows(values, capacity))
                            for name, values in zip(names, saved)])
            old.destroy()
        self.pairs = new
        self.broadphase.compile_pair_kernels(new)
        self._compile_pair_kernels(new)

    def destroy(self):
        if self.pairs is not None:
            self.pairs.destroy()
        for t in self.trees:
            t.destroy()
        self.trees.clear()
        self.worker_pool.destroy()

    # ------------------------------------------------------------------ kernels
    def _compile_particle_kernels(self):
        full = self.holding
        for variant in self._variants.values():
            self.holding = variant["holding"]       # (make_drift reads the engine's hooks)
            self.minimum_image, particle, drift = make_drift(self)
            variant["drift"] = (particle, drift)
        self.holding = full
        self.drift_particle, self._drift = self._variants[full.any]["drift"]

    def select_step(self):
        """Run the step with the holder's hooks while its last judgement held particles, else
        the one without them (the same results: every flag is 1). Called after each
        judgement (the rebuilds) and where a run of steps begins (after a restore)."""
        variant = self._variants[self.holding.holds_any()]
        self.drift_particle, self._drift = variant["drift"]
        if "pairs" in variant:
            (self._pair_forces, self._gather, self._run_steps,
             self._run_worker_steps) = variant["pairs"]

    def _compile_pair_kernels(self, p: PairState):
        """The step's kernels for the pair list ``p``, once per variant (with and without the
        holding hooks; each compiled on first use), then the one to run (select_step)."""
        full = self.holding
        for variant in self._variants.values():
            self.holding = variant["holding"]       # (the stages read the engine's hooks)
            self.drift_particle = variant["drift"][0]
            self._compile_pair_variant(p)
            variant["pairs"] = (self._pair_forces, self._gather, self._run_steps,
                                self._run_worker_steps)
        self.holding = full
        self.select_step()

    def _compile_pair_variant(self, p: PairState):
        """The step's ti.funcs and kernels for the pair list ``p``: one factory per contact
        kind (pairs: pair_stage.py; plane walls: contacts/planes.py; mesh triangles:
        bodies/mesh_contacts.py), the gather that sums them (gather_stage.py), and the
        drivers' runs of steps (drivers.py)."""
        s = self.state
        model = self.model
        real = model.real
        effects = model.effect_list
        # the contact geometry of each kind and the contact law composed from the enabled
        # effects (contacts/): the same law runs on pairs, planes and triangles
        geometry = make_geometry(real, model.heat)
        sphere_surface = geometry[1]
        # the history values the enabled effects keep, and one load/store/clear of them per
        # storage: the neighbour entries and the (particle, plane wall) slots
        members = history_members(effects)
        _, _, History = contact_types(real, members)
        pair_history = make_history_io(History, members,
                                       {m: getattr(p, m + "_history") for m in members})
        n_walls = len(model.scene.walls)
        heat = model.heat
        wall_force = self.wall_force
        wall_heat = self.wall_heat if heat else None
        conducted_of = make_conducted_of(s, model.conducted_field)
        plane_contacts = None
        if n_walls:
            wall_history = make_history_io(History, members,
                                           {m: getattr(s, "wall_" + m + "_history")
                                            for m in members})
            plane_contacts = make_plane_contacts(
                s, self.plane_walls, sphere_surface,
                make_contact_law(effects, "plane", real, self.context), wall_history,
                wall_force, wall_heat, heat, conducted_of,
                margin_fraction(model.contact_effects, "plane"))
        mesh_contacts = shields = place_candidates = None
        if self.mesh is not None:
            mesh_contacts = self.mesh.make_particle_contacts(
                make_contact_law(effects, "triangle", real, self.context),
                make_contact_law(effects, "surface", real, self.context), sphere_surface)
            # a plate between two spheres: no pair contact through it; both read each
            # particle's candidates as placed this step, before any pair (place_candidates)
            shields = self.mesh.make_shields()
            place_candidates = self.mesh.make_place_candidates()
        has_mesh = mesh_contacts is not None
        pairs = PairStage(self, p, geometry, pair_history, conducted_of, shields,
                          place_candidates)
        gathers = GatherStage(self, p, conducted_of, plane_contacts, mesh_contacts)
        pair_particle, pair_forces = pairs.pair_particle, pairs.pair_forces
        gather_particle, gather = gathers.gather_particle, gathers.gather
        vec0 = ti.Vector([0.0, 0.0, 0.0])
        pool = self.worker_pool

        self._pair_forces = self.serial_switch(pair_forces)
        self._gather = self.serial_switch(gather)

        # runs of steps (serial mode): the cell stage of each effect as a ti.func
        cell_funcs = tuple(e.cell_func(self.context) for e in self.model.cell_effects) if self.runs else ()
        set_frames = self.mesh.frames.set_frames if has_mesh else None
        flags = self.flags
        n_wall_slots = max(n_walls, 1)

        @ti.func
        def begin_step(j, t, last, record_last, full_first, leader):
            """What step j of a run (at ``t``, s; ``last`` of the run) needs before its pair
            stage, done by the thread ``leader`` marks: the wall loads zeroed when this step
            books them, the bodies' frames set. Returns (record, full): whether the step books
            the wall loads, whether it follows a rebuild (held particles' pairs are judged then)."""
            record = 0
            if last and record_last != 0:
                record = 1
                if leader:
                    for w in range(n_wall_slots):
                        wall_force[w] = vec0
                        if ti.static(heat):
                            wall_heat[w] = 0.0
            if ti.static(has_mesh):
                if leader:
                    set_frames(ti.cast(t, real))
            full = 0
            if j == 0:
                full = full_first
            return record, full

        # the step's functions, which every driver runs (drivers.py)
        step = drivers.StepFunctions(
            pair_particle=pair_particle, gather_particle=gather_particle, begin_step=begin_step,
            before_pairs=place_candidates, cell_funcs=cell_funcs, flags=flags, state=s,
            real=real)
        self._run_steps = drivers.compile_run_steps(step)
        self._run_worker_steps = (drivers.compile_run_worker_steps(step, pool) if pool.workers
                                  else None)

    # ------------------------------------------------------------------ driver
    def start(self, n: int) -> int:
        """Build the first neighbour list and the initial accelerations (no time advance)."""
        if self.mesh is not None:
            self.mesh.update_frames(self.time)
        self.choose_loop_mode(n)
        self.flags[Flag.REBUILD] = 0          # (set by the insertion of the initial fill)
        self.count = self.broadphase.rebuild(n)
        for x in self.model.rebuild_effects:
            x.after_rebuild(self.context, self.count, self.time)
        self.select_step()
        if self.serial and self.runs:
            # one step of no length in the kernel the runs use (nothing else to compile)
            self._run_steps(self.count, 0.0, self.time, 0.0, 1, 1, 0, 0)
            return self.count
        self._pair_forces(self.count, 0.0, 1)
        for e in self.model.cell_effects:
            e.after_pairs(self.context, self.count, 0.0)
        self._gather(self.count, 0.0, 0, 0, self.time)
        return self.count

    def rebuild(self, n: int):
        """Drop dead particles, re-sort and rebuild the neighbour lists; first the
        ``before_rebuild`` hook, which may insert particles (mid-step: drifted, forces
        pending) so that this rebuild lists them too."""
        if self.before_rebuild is not None:
            self.before_rebuild(self)
            n = self.count
        self.flags[Flag.REBUILD] = 0
        if self.process is not None and self.process.log_enabled:
            batch = self.process.drain()
            if batch is not None:
                self.removed_batches.append(batch)
        self.choose_loop_mode(n)
        self.count = self.broadphase.rebuild(n)
        self.broadphase.list_age = 0
        self.flags[Flag.DEAD_IN_SLOTS] = 0
        for x in self.model.rebuild_effects:
            x.after_rebuild(self.context, self.count, self.time)
        self.select_step()

    def advance(self, steps: int, record_last: bool = False):
        """Advance ``steps`` time steps of ``self.model.dt``: in runs of steps per launch in the
        serial mode (``runs``), else two parallel launches per step."""
        self.select_step()
        if self.serial and self.runs:
            drivers.advance_in_runs(self, steps, record_last)
            return
        pool = self.worker_pool
        if pool.give_way:
            pool.workers = 0
        if pool.workers and self._run_worker_steps is not None:
            drivers.advance_in_runs(self, steps, record_last, on_workers=True)
            return
        drivers.advance_per_stage(self, steps, record_last)

    def measure(self) -> dict:
        """The state's sums at this instant (measure.py): kinetic_energy J, max_speed m/s,
        non_finite, and what the effects declare (Effect.measure_funcs; with heat
        thermal_energy J, mean_temperature K, thermal_step_ratio; drying: mean_moisture
        kg/kg, evaporated_mass kg)."""
        if self._measure is None:
            self._measure = Measure(self)
        return self._measure(self.count)

    @property
    def lost(self) -> int:
        return int(self.flags[Flag.LOST])

    @property
    def alive_count(self) -> int:
        """Particles in the simulation now (slots in use minus those removed since the last
        rebuild)."""
        return self.count - int(self.flags[Flag.DEAD_IN_SLOTS])

    def insert(self, arrays: dict):
        """Put new particles into the slots after the last one in use and flag a rebuild
        (insertion.py: the one way particles are created, the initial fill's too)."""
        self.count = self.insertion.insert(self.count, arrays)

    def occupied(self) -> dict:
        """What the slots in use hold (insertion.Insertion.occupied)."""
        return self.insertion.occupied(self.count)
