"""Gas drag: the mechanics-only [gas] keys, ``DragSettings`` and where a drag comes from
(the effect is effect.py). Plain Python (no Taichi)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from ...errors import SceneError
from ... import air
from ...scene.keys import Key, Section, given, register, type_name

MODELS = ("di_felice", "schiller_naumann")
THROUGH_BED_HELP = ("true: the gas is forced through every packing at its superficial velocity "
                    "(a packed or fluidised bed on a distributor); false: it flows round packings "
                    "(a drum's bed, a flight's load) and drags only the particles that no contact "
                    "touches (the curtains)")

SECTION = register(Section("gas", "A gas that drags the particles (one-way coupled), without "
                           "heat transfer; with [thermal], give the gas in [thermal.gas]", (
    Key("velocity", "vector", "the gas's superficial velocity (uniform)", unit="speed",
        default=None),
    Key("density", "quantity", "the gas's density", unit="density", default=air.DENSITY,
        minimum=0.0, exclusive_minimum=True),
    Key("viscosity", "quantity", "the gas's dynamic viscosity", unit="viscosity",
        default=air.VISCOSITY, minimum=0.0, exclusive_minimum=True),
    Key("drag", "choice", "the drag law: Di Felice (local voidage from the cell grid) or "
        "Schiller-Naumann (a dilute particle)", default="di_felice", choices=MODELS),
    Key("through_bed", "boolean", THROUGH_BED_HELP, default=False),
), owner=__name__, reader=lambda table, parser: read(table, parser),
   derive=lambda parser: derive(parser), after=("thermal",),
   builds="taichi_dem.effects.drag.effect:build",
   speed_bound=lambda scene, settings: carried_speed(settings),
   schema_rules=lambda: [given("velocity")]))


# the series this effect writes (sensors/series.py)
from ...scene.keys import Series  # noqa: E402

SERIES = (Series("gas/drag_force", "N", "the gas's pull on all particles in the last step",
                 "(3,)"),)


@dataclass(frozen=True)
class DragSettings:
    """Drag from a gas on the particles (effects/drag/effect.py), one-way coupled: ``model``
    "di_felice" (local voidage from the cell grid) or "schiller_naumann" (dilute); the gas's
    superficial ``velocity`` m/s (uniform), ``density`` kg/m^3 and ``viscosity`` Pa s;
    ``through_bed``: the gas forced through packings (else round them, dragging only the
    particles no contact touches). From the mechanics-only [gas] section or from
    [thermal.gas] with ``drag`` (and ``drag_through_bed``)."""
    model: str
    velocity: tuple
    density: float
    viscosity: float
    # whether the gas flows through packings (a bed on a distributor) or round them (a drum):
    # then a particle that any contact touches feels no gas (effect.py)
    through_bed: bool = False


# the voidage of a loose packing: the gas between its particles moves at U / 0.4
LOOSE_VOIDAGE = 0.4


def carried_speed(settings: DragSettings) -> float:
    """The fastest the gas can carry a particle, m/s (for the time step and the divergence
    guard): its interstitial speed in a loose packing, |U| / 0.4. A particle dragged along
    approaches the gas's speed and no more (gravity's part is bounded apart); Di Felice's
    voidage is clamped at 0.1, but a bed that dense does not move at the gas's speed."""
    return math.sqrt(sum(c * c for c in settings.velocity)) / LOOSE_VOIDAGE


def read(table, parser) -> DragSettings:
    """The mechanics-only [gas] section (``parser``: the loader's, whose ``settings`` hold
    [thermal] already): refused beside a [thermal.gas], which gives its drag itself."""
    file = parser.source
    heat = parser.settings.get("thermal")
    if heat is not None and heat.gas is not None:
        raise SceneError(file, "gas", "the scene has a [thermal.gas] already: give its drag "
                                      "there (drag = \"di_felice\"), not a second gas")
    if not isinstance(table, dict):
        raise SceneError(file, "gas", f"expected a table, got {type_name(table)}")
    SECTION.check(table, file, "gas")
    if "velocity" not in table:
        SECTION.read(table, file, "gas", only=("drag",))
        raise SceneError(file, "gas.velocity", "required: the gas's superficial velocity, m/s")
    v = SECTION.read(table, file, "gas", defaults=True)
    return DragSettings(model=v["drag"], velocity=v["velocity"], density=v["density"],
                        viscosity=v["viscosity"], through_bed=bool(v["through_bed"]))


def derive(parser) -> Optional[DragSettings]:
    """The drag of a [thermal.gas] with drag = "di_felice" | "schiller_naumann" (its gas's
    velocity, density and viscosity, and drag_through_bed), when the scene has no [gas];
    else None."""
    heat = parser.settings.get("thermal")
    heat_gas = heat.gas if heat is not None else None
    if heat_gas is not None and heat_gas.drag != "none":
        return DragSettings(model=heat_gas.drag, velocity=heat_gas.velocity,
                            density=heat_gas.density, viscosity=heat_gas.viscosity,
                            through_bed=heat_gas.drag_through_bed)
    return None
