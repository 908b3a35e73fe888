"""What an effect declares: its stage, the fields and pair tables it needs, and its kernels.

An ``Effect`` is one physical effect of a scene, built by ``enabled_effects(scene)`` only when
the scene calls for it. The engine composes the step from these declarations:

stage      where it runs
---------  -------------------------------------------------------------------------------
contact    in the contact law (contacts/law.py), on each contact of the ``kinds`` it names
           ("pair", "plane", "triangle", "surface"): ``contact_func(engine)`` returns a
           ti.func; mechanical effects ``(contact, response, history, dt) -> (response,
           history)``, heat effects ``(contact, response) -> response`` adding a conductance
particle   in the per-particle pass (gather), after the contacts: ``particle_func(engine)``
           returns a ti.func ``(i, load) -> load`` adding to the particle's load (force N,
           torque N m, acceleration m/s^2, heat W, conductance W/K)
integrate  the update of the particle's state from its load (velocity Verlet, temperature,
           drying); run by the engine in that order
cell       between the pair stage and the particle stage, over cells: ``after_pairs(engine,
           n, dt)`` launches its kernel (the drag's solid per contact cell, the plug-flow
           gas's march); ``cell_func(engine)`` returns the same work as a ti.func ``(n, dt)``
           for a loop that is already serial (engine/drivers.py run_steps: several steps per launch);
           an effect without one keeps its scene to one launch per kernel per step
process    factories and outlets (process/); observe: sensors (sensors/)

Fields are declared by name: ``particle_fields`` (per particle, ``{name: (is_vector, kind)}``,
kind "real" | "int" | "f64"), ``contact_fields`` (state each contact carries from step to
step, e.g. the tangential spring: per neighbour entry, per particle and plane wall, per mesh
contact; zeroed when the contact opens and on insertion), ``pair_fields`` (per neighbour entry,
the partner's share of a pair effect's output). They are allocated only when an effect that
declares them is enabled, permuted with the particles, carried across rebuilds and saved in
checkpoints by name. ``tables``: material-pair tables (M x M) by name, uploaded from
``table_values``. ``check(sim, measured)``: the effect's stability check at each output sample
(the explicit temperature update's limit). ``margin``: a contact margin (fraction of the particle radius) within which
non-touching contacts are handed to the law (heat through the gas near a contact).
"""
from __future__ import annotations


class EffectContext:
    """What an effect sees of the simulation it runs in, from explicit objects: the ``model``
    (engine/model.py: ``real`` precision, ``dt`` s, ``grid``, ``material_names`` in table
    order, ``species`` (kinds of particle), ``max_radius`` m), the run-time scene ``values``
    (engine/values.py), the material-pair device ``table`` by name, the particle ``state``
    (its declared fields among them), the neighbour cells and mesh contacts once built
    (``broadphase``, ``mesh``: ``attach``), the step's loop mode (``serial``,
    ``serial_switch``, from ``step``) and ``effect(name)``, another enabled effect.

    Read-only, and nothing else: an effect keeps what it allocates on itself, reads its
    scene settings from its own constructor's arguments (effects/registry.py), and never the
    engine or the raw scene (tests/unit/test_effect_boundary.py)."""

    __slots__ = ("_model", "_values", "_table", "_state", "_step", "_parts")

    def __init__(self, model, values, table: dict, state, step):
        """``step``: what runs the kernels (the Engine), asked only for its loop mode."""
        for name, value in (("_model", model), ("_values", values), ("_table", table),
                            ("_state", state), ("_step", step), ("_parts", {})):
            object.__setattr__(self, name, value)

    def attach(self, name: str, part) -> None:
        """Make ``broadphase`` or ``mesh`` visible once the engine has built it."""
        assert name in ("broadphase", "mesh"), name
        self._parts[name] = part

    real = property(lambda self: self._model.real, doc="ti.f32 or ti.f64")
    dt = property(lambda self: self._model.dt, doc="the time step, s")
    grid = property(lambda self: self._model.grid, doc="the neighbour search's cells")
    material_names = property(lambda self: self._model.tables.names,
                              doc="the materials in table order")
    species = property(lambda self: self._model.species,
                       doc="((material index, radius m), ...) or None")
    max_radius = property(lambda self: self._model.max_radius, doc="the largest radius, m")
    values = property(lambda self: self._values, doc="scene values read at run time")
    table = property(lambda self: self._table, doc="material-pair device tables by name")
    table_values = property(lambda self: self._model.table_values,
                            doc="the same tables on the host (numpy, f64) by name")
    state = property(lambda self: self._state, doc="the particle state (engine/state.py)")
    broadphase = property(lambda self: self._parts.get("broadphase"),
                          doc="the neighbour cells and pair list, once built")
    mesh = property(lambda self: self._parts.get("mesh"),
                    doc="the mesh contacts, once built (None without bodies)")
    serial = property(lambda self: self._step.serial,
                      doc="whether the step's loops run on one thread now")

    def serial_switch(self, kernel):
        """``kernel`` launched in the step's loop mode (Engine.serial_switch)."""
        return self._step.serial_switch(kernel)

    def __getattr__(self, name):
        raise AttributeError(f"an effect sees the model and the state, not {name!r} "
                             "(effects/base.py EffectContext)")

    def __setattr__(self, name, value):
        raise AttributeError(f"an effect cannot set {name!r} on the simulation: keep it on "
                             "the effect")

    def effect(self, name: str):
        """The enabled effect called ``name``, or None."""
        return self._model.effect(name)


def particle_load(real):
    """The load a particle stage adds to (``particle_func``, ``inserted_func``): a Taichi
    struct of ``acceleration`` m/s^2 (3-vector), ``heat`` W and ``conductance`` W/K, and
    ``touching`` (i32, read-only for the effects): 1 when a contact pushes on the particle in
    this step or it is held in a packing (mobility: its contacts are skipped, and it rests on
    them), else 0 (the gas's drag reads it: a gas that flows round packings drags only the
    particles that touch nothing)."""
    import taichi as ti
    vec3 = ti.types.vector(3, real)
    return ti.types.struct(acceleration=vec3, heat=real, conductance=real, touching=ti.i32)


class Effect:
    """One enabled physical effect (see the module docstring for what each attribute means)."""

    name = "effect"
    stage = "particle"
    # its place in its stage: the names of the effects it must run after, or before, where
    # both are enabled (effects/registry.py order_effects); otherwise the registry's order
    after: tuple[str, ...] = ()
    before: tuple[str, ...] = ()
    kinds: tuple[str, ...] = ()
    mechanical = False
    # a contact effect whose ti.func depends on the kind: contact_func(ctx, kind)
    per_kind = False
    # an effect that holds particles still between rebuilds, or carries them with the frame of
    # body ``carrier_body`` (>= 0): it owns the flag ``particle_active`` and the hooks of
    # engine/holding.py (make_rigid_drift, make_rigid_velocity, make_carried_load)
    holds_particles = False
    carrier_body = -1
    # the most steps the effect lets the neighbour lists age without a rebuild (its
    # ``after_rebuild`` judges something that goes stale otherwise: mobility's cells in a bed
    # that has come to rest, where nothing else asks for a rebuild); None: no limit
    rebuild_within_steps: int | None = None
    # the particle field whose differences the contact law turns into heat (the temperature
    # effect: "temperature", K): the contacts then carry heat (W) and conductance (W/K) into
    # the particles' loads (``particle_load``), and the engine allocates their sums
    conducted_field: str | None = None
    # it conducts heat to walls and bodies that have a temperature (their heat series, the
    # walls' temperatures uploaded)
    heats_walls = False
    # the energy the effect brings into the particles from outside the balance of
    # thermal/energy_balance.py: {series name: sign}, each series J since the start, written by the
    # effect's ``sample`` (+1: into the particles, -1: out of them)
    energy_terms: dict = {}
    margin = 0.0
    # the scene key that sets ``margin`` and how to do without it, named where the margin
    # does not fit a periodic axis (run/simulation.py _check_periodic_axes)
    margin_key = ""
    margin_advice = ""
    particle_fields: dict = {}
    contact_fields: dict = {}
    pair_fields: dict = {}
    tables: tuple[str, ...] = ()

    def __init__(self, description: str = "", name: str | None = None, stage: str | None = None):
        self.description = description
        if name is not None:
            self.name = name
        if stage is not None:
            self.stage = stage

    def table_values(self, scene, tables) -> dict:
        # (the one place an effect meets the scene: the material-pair tables are built from
        # its materials and interactions once, before anything is allocated)
        """{table name: (M, M) numpy array} for the tables this effect declares; by default
        the attribute of that name of the scene's ``PairTables``."""
        return {name: getattr(tables, name) for name in self.tables}

    def allocate(self, ctx, tree) -> None:
        """Allocate what the effect holds beyond its declared fields (e.g. a gas stream)."""

    def upload(self, ctx) -> list:
        """The first values of what ``allocate`` made: a list of (field, host array) pairs,
        which the engine writes with the material-pair tables in one copy kernel
        (engine/transfer.py; a ``from_numpy`` per field compiles a kernel each)."""
        return []

    def prepare(self, ctx) -> None:
        """Compile what needs the engine's parts (the broadphase's cells, the mesh), once
        they are built (ctx.broadphase, ctx.mesh)."""

    def after_rebuild(self, ctx, n: int, time: float) -> None:
        """Work after each neighbour-list rebuild, before the step that follows (``n``
        particle slots, at ``time`` s); only effects that override it are called."""

    def run_observers(self, sim) -> dict:
        """The observers of the run this effect brings beside the sensors' ({name: an object
        with ``sample(values, now)`` and ``state_dict``/``load_state_dict``}; the heat's energy
        balance, thermal/energy_balance.py), built after the sensors (sensors/__init__.py
        ``build_sensors``) so that they read the samples' loads and accounts."""
        return {}

    def check(self, sim, measured: dict) -> None:
        """A stability check at every output sample (``measured``: Engine.measure()): raise
        taichi_dem.DivergenceError to stop the run, or warn. Effects that have one override
        it; the run driver attaches only those (run/simulation.py)."""

    def source_values(self, scene, source, names, material, mass) -> dict:
        """{state field: (n,) array}: what this effect gives the n particles a source brings
        in - an initial fill (``source`` its scene entry) or a factory's batch - by name
        (the heat's temperature K, moisture kg/kg and 1 / thermal mass 1/(J/K)); ``names``
        the sorted material names, ``material`` (n,) indices into them, ``mass`` (n,) kg.
        Written by the same insertion as every other field (engine/insertion.py)."""
        return {}

    def inserted_func(self, ctx):
        """What an inserted particle starts with from this effect: it is inserted clear of
        every contact, so its first half step's acceleration is the sum of the effects that
        act on a free particle (gravity, a body force). A ti.func ``(i, load) -> load`` as
        ``particle_func``'s, or None (this effect gives a free particle nothing)."""
        return None

    def integrate_func(self, ctx):
        """The integrate stage's update of a particle's own state from its load (after the
        contacts and the particle stage): a ti.func ``(i, load, dt)`` (``load`` as
        ``particle_func``'s: heat W, conductance W/K; dt s), or None (the default: an effect
        whose integration another one runs, or the engine's velocity Verlet)."""
        return None

    def inserted_values(self, ctx):
        """The values this effect gives an inserted particle from the arrays the fill or a
        factory hands the insertion (engine/insertion.py): a list of (array name, ti.func
        ``(i, value)`` writing the f64 ``value`` into particle i's state). An effect that
        gives any sets all its particle fields (the others are zeroed for a new particle).
        [] by default."""
        return []

    def measure_funcs(self, ctx):
        """What the effect adds to the state's sums at an output sample (engine/measure.py),
        or None: ``(reset, particle, fields, read)``: ti.funcs ``reset()`` and
        ``particle(i)`` (for every live particle, reducing by atomics into the effect's own
        fields), the ``fields`` the host reads after the kernel, and ``read(arrays) -> dict``
        of the measured values from their host copies (``"non_finite": True`` joins the
        engine's flag)."""
        return None

    def contact_func(self, ctx):
        raise NotImplementedError(f"{self.name} is not a contact effect")

    def particle_func(self, ctx):
        raise NotImplementedError(f"{self.name} is not a particle effect")

    def __repr__(self):
        return f"<effect {self.name} ({self.stage})>"
