"""What a simulation *is*, built once from the scene before anything is allocated: the
``Model``. Frozen: the state (state.py) is allocated from it, the step (stepper.py) and its
drivers (drivers.py) are compiled from it, and nothing changes it afterwards.

The scene (scene/model.py) says what the user asked for; the model adds what the engine
derives from it once: the enabled effects in step order grouped by stage, the fields they
declare, the material-pair tables, the contact margins, the cell grid, the species, the time
step and the skin."""

from dataclasses import dataclass

from ..contacts.law import margin_fraction
from ..effects import enabled_effects
from ..setup.pair_tables import PairTables
from .grid import GridSpec
from ..setup.memory import allocated_slots

# In f32, positions farther than this from the origin (m) carry a residual (split positions:
# engine/precision.py): the f32 spacing there, 1.2e-7 m, is what a resting bed would jitter by
SPLIT_POSITIONS_BEYOND = 1.0


def split_positions(scene) -> bool:
    """Whether an f32 scene's positions reach farther than SPLIT_POSITIONS_BEYOND from the
    origin (its domain's farthest coordinate): then each keeps a residual."""
    if scene.simulation.precision != "f32":
        return False
    reach = max(max(abs(v) for v in scene.domain.min), max(abs(v) for v in scene.domain.max))
    return reach > SPLIT_POSITIONS_BEYOND


@dataclass(frozen=True, eq=False)
class Model:
    """The frozen model of one simulation (see the module docstring). Lengths m, times s."""

    scene: object                 # the validated Scene (scene/model.py): plain data
    tables: PairTables            # material-pair tables (setup/pair_tables.py)
    real: object                  # ti.f32 or ti.f64
    dt: float                     # time step, s
    skin: float                   # Verlet skin, m
    max_radius: float             # the largest radius the particles (and factories) have, m
    capacity: int                 # particle slots allocated: a bucket (engine/values.py)
    particle_limit: int           # particle slots the scene may fill (fills + factories)
    # ((material index, radius m), ...) of every kind of particle, or None (a distribution):
    # what per-species tables (the gas gap's) are built for
    species: "tuple | None"
    effect_list: tuple            # the enabled effects, in step order (effects/registry.py)
    contact_effects: tuple        # ... of stage "contact" (the contact law)
    particle_effects: tuple       # ... of stage "particle" (the gather)
    cell_effects: tuple           # ... with a cell stage between pairs and particles
    particle_fields: dict         # {name: (is_vector, kind)} every effect declares
    contact_fields: dict          # the contact history the contact effects keep
    pair_fields: dict             # per neighbour entry: the partner's shares of pair effects
    # pairs within this fraction of the larger radius are listed and handed to the contact
    # law too (the gas gap near a contact); 0: touching pairs only
    pair_margin: float
    grid: GridSpec                # the cells of the neighbour search over the domain
    # {name: (M, M) numpy array}: the material-pair tables the enabled effects read, under
    # their physics names (the one place an effect meets the scene: Effect.table_values)
    table_values: dict

    @classmethod
    def build(cls, scene, tables: PairTables, real, dt: float, skin: float,
              max_radius: float, capacity: int, species=None, effects=None) -> "Model":
        """The model of ``scene`` (``effects``: its enabled effects when already built,
        enabled_effects(scene) otherwise; they are built once per simulation)."""
        effect_list = tuple(effects) if effects is not None else enabled_effects(scene)
        contact = tuple(e for e in effect_list if e.stage == "contact")
        particle_fields, contact_fields, pair_fields = {}, {}, {}
        for e in effect_list:
            particle_fields.update(e.particle_fields)
        if split_positions(scene):
            # the part of each position f32 cannot hold (engine/precision.py)
            particle_fields["position_residual"] = (True, "real")
        for e in contact:
            contact_fields.update(e.contact_fields)
            pair_fields.update(e.pair_fields)
        pair_margin = margin_fraction(contact, "pair")
        table_values = {}
        for e in effect_list:
            for name, values in e.table_values(scene, tables).items():
                table_values.setdefault(name, values)
        # the arrays are allocated for a bucket of slots (no fewer than a floor), so that
        # scenes whose counts differ a little share their kernels; the factories fill no
        # more than the scene's own
        slots = allocated_slots(capacity)
        # (the cell arrays sized for any skin: a skin set by the time step compiles nothing)
        grid = GridSpec(scene.domain.min, scene.domain.max, scene.domain.periodic,
                        (2.0 + pair_margin) * max_radius + skin, capacity,
                        least_cutoff=(2.0 + pair_margin) * max_radius)
        return cls(scene=scene, tables=tables, real=real, dt=dt, skin=skin,
                   max_radius=max_radius, capacity=slots, particle_limit=int(capacity),
                   species=species,
                   effect_list=effect_list, contact_effects=contact,
                   particle_effects=tuple(e for e in effect_list if e.stage == "particle"),
                   cell_effects=tuple(e for e in effect_list if hasattr(e, "after_pairs")),
                   particle_fields=particle_fields, contact_fields=contact_fields,
                   pair_fields=pair_fields, pair_margin=pair_margin, grid=grid,
                   table_values=table_values)

    # what the step's kernels branch on at compile time (ti.static)
    @property
    def effect_names(self) -> frozenset:
        return frozenset(e.name for e in self.effect_list)

    def effect(self, name: str):
        """The enabled effect called ``name``, or None."""
        for e in self.effect_list:
            if e.name == name:
                return e
        return None

    @property
    def conducted_field(self) -> "str | None":
        """The particle field whose differences the contact law turns into heat (the
        temperature, K), as an enabled effect declares it (Effect.conducted_field); None: the
        contacts carry no heat, and none of its sums is allocated or compiled."""
        for e in self.effect_list:
            if e.conducted_field is not None:
                return e.conducted_field
        return None

    @property
    def heat(self) -> bool:
        """The contacts carry heat (W) and conductance (W/K) into the particles' loads."""
        return self.conducted_field is not None

    def carries(self, name: str) -> bool:
        """Whether the particles carry the field ``name`` (an enabled effect declares it)."""
        return name in self.particle_fields

    @property
    def split_positions(self) -> bool:
        """Positions carry a residual (f32 far from the origin: engine/precision.py)."""
        return "position_residual" in self.particle_fields

    @property
    def pair_heat(self) -> bool:
        """A pair effect conducts heat (partner heat shares at the entries)."""
        return "partner_heat" in self.pair_fields

    @property
    def heats_walls(self) -> bool:
        """Heat is conducted to walls and bodies with a temperature (their heat series): an
        effect declares ``heats_walls``."""
        return any(e.heats_walls for e in self.effect_list)

    @property
    def rebuild_within_steps(self) -> int | None:
        """The most steps between neighbour rebuilds any enabled effect allows
        (Effect.rebuild_within_steps), None where none limits it."""
        limits = [x.rebuild_within_steps for x in self.effect_list
                  if x.rebuild_within_steps is not None]
        return min(limits) if limits else None

    @property
    def rebuild_effects(self) -> tuple:
        """The effects with work after each neighbour-list rebuild (Effect.after_rebuild)."""
        from ..effects.base import Effect
        return tuple(x for x in self.effect_list
                     if type(x).after_rebuild is not Effect.after_rebuild)
