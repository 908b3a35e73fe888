"""[viscous_damping]: its keys and settings (the effect is effect.py). Plain Python."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...errors import SceneError
from ...scene.keys import REQUIRED, Key, Section, register, type_name


@dataclass(frozen=True)
class DampingSettings:
    """a = -v / ``time_constant`` (s) on every moving particle."""
    time_constant: float


# The damping is an explicit load -v / tau in the velocity Verlet step: per step the velocity
# is multiplied by about (1 - dt / tau), which overshoots (flips sign) for dt > tau and grows
# without bound for dt > 2 tau (time_constant = 1e-6 s with dt = 1.2e-5 s lost all 200
# particles of a pile in 0.02 s). At tau >= 5 dt the factor 0.8 is within 2.5 % of the exact
# exp(-dt / tau) = 0.82 and ten times inside the stability limit: the decay is resolved.
MIN_STEPS_PER_TIME_CONSTANT = 5


def step_problem(settings: DampingSettings, dt: float):
    """Why the time step ``dt`` (s) cannot resolve the damping: (its key, a reason), or
    None."""
    least = MIN_STEPS_PER_TIME_CONSTANT * dt
    if settings.time_constant < least:
        return "time_constant", (f"{settings.time_constant:g} s is shorter than {MIN_STEPS_PER_TIME_CONSTANT} "
                f"time steps (dt = {dt:.3g} s): the explicit damping would overshoot or "
                f"diverge; use time_constant >= {least:.3g} s")
    return None


def read(table: Any, parser) -> DampingSettings:
    """The section, checked against its declaration (``parser``: the loader's, for the file
    name in errors)."""
    if not isinstance(table, dict):
        raise SceneError(parser.source, "viscous_damping", f"expected a table, got {type_name(table)}")
    return DampingSettings(**SECTION.read(table, parser.source, "viscous_damping"))


SECTION = register(Section("viscous_damping", "Background viscous damping for settling: "
                           "every moving particle's velocity relaxes to rest, a = -v / "
                           "time_constant (off without this section)", (
    Key("time_constant", "quantity", "the velocity falls by e in this time; at least 5 time "
        "steps (the explicit decay is resolved)", unit="time",
        default=REQUIRED, minimum=0.0, exclusive_minimum=True),
), owner=__name__, reader=read, builds="taichi_dem.effects.viscous_damping.effect:build",
   step_problem=step_problem))
