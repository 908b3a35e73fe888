"""The body force effect: a particle stage adding factor x acceleration to each particle's
acceleration, a free particle's first acceleration when inserted, and its series."""
import numpy as np
import taichi as ti

from ..base import Effect
from .settings import factors


class BodyForce(Effect):
    name = "body_force"
    stage = "particle"
    tables = ("body_force_factor",)

    def __init__(self, description: str, acceleration):
        super().__init__(description)
        self.acceleration = tuple(float(a) for a in acceleration)    # m/s^2

    def table_values(self, scene, tables) -> dict:
        """The material-pair table it reads: row m holds material m's factor."""
        per_material = factors(scene)
        column = np.array([per_material[name] for name in tables.names])
        return {"body_force_factor": np.repeat(column[:, None], len(column), axis=1)}

    def particle_func(self, ctx):
        s, factor = ctx.state, ctx.table["body_force_factor"]
        # read at run time (engine/values.py): another acceleration compiles nothing
        acceleration = ctx.values.vector("body_force_acceleration", self.acceleration)

        @ti.func
        def body_force(i, load):
            m = s.material[i]
            load.acceleration += factor[m, m] * acceleration()
            return load

        return body_force

    def inserted_func(self, ctx):
        """An inserted particle starts in free flight under the force too."""
        return self.particle_func(ctx)

    def sample(self, values: dict, n: int, measured: dict) -> None:
        """Its series at an output sample: sum of m x factor x acceleration over the moving
        particles inside, N."""
        s, ctx_factor = self._state, self._factor
        alive = s.alive.to_numpy()[:n] != 0
        moving = alive & (s.inverse_mass.to_numpy()[:n] > 0)
        mass = s.mass.to_numpy()[:n].astype(np.float64)
        factor = np.diag(ctx_factor.to_numpy()).astype(np.float64)[s.material.to_numpy()[:n]]
        values["body_force/force"] = np.sum(mass * factor * moving) * np.array(self.acceleration)

    def allocate(self, ctx, tree) -> None:
        # (what sample reads, kept at allocation: an effect sees the state through ctx only)
        self._state, self._factor = ctx.state, ctx.table["body_force_factor"]


def build(scene, settings) -> list:
    """The effect objects for a scene's [body_force] ``settings`` (BodyForceSettings)."""
    a = settings.acceleration
    return [BodyForce(f"body force, ({a[0]:g}, {a[1]:g}, {a[2]:g}) m/s^2 x each material's "
                      "body_force_factor", a)]
