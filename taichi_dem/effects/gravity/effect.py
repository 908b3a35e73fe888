"""Uniform gravity: every moving particle accelerates at g (m/s^2)."""
import taichi as ti

from ..base import Effect


def build(scene, settings) -> list:
    """The gravity effect of a scene whose [simulation] gravity is nonzero (``settings``:
    its GravitySettings)."""
    return [Gravity("uniform gravity", settings.acceleration)]


class Gravity(Effect):
    name = "gravity"
    stage = "particle"

    def __init__(self, description, gravity):
        super().__init__(description)
        self.gravity = tuple(float(g) for g in gravity)

    def particle_func(self, ctx):
        # read at run time (engine/values.py): a scene with another gravity compiles nothing
        g = ctx.values.vector("gravity", self.gravity)

        @ti.func
        def gravity(i, load):
            load.acceleration += g()
            return load

        return gravity

    def inserted_func(self, ctx):
        """A particle inserted in free flight starts at g."""
        return self.particle_func(ctx)
