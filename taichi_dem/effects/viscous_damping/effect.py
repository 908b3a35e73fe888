"""The viscous damping effect: a particle stage adding -v / tau to each moving particle's
acceleration (v its velocity at the half step, as every velocity-dependent load in the
step)."""
import taichi as ti

from ..base import Effect


class ViscousDamping(Effect):
    name = "viscous_damping"
    # its acceleration added after gravity's, as it always was (gravity was built first):
    # the order of the sums, and so the last bits of every result, stay what they were
    after = ("gravity",)
    stage = "particle"

    def __init__(self, description: str, time_constant: float):
        super().__init__(description)
        self.rate = 1.0 / float(time_constant)     # 1/s

    def particle_func(self, ctx):
        s = ctx.state
        rate = self.rate

        @ti.func
        def viscous_damping(i, load):
            load.acceleration -= ti.static(rate) * s.velocity[i]
            return load

        return viscous_damping


def build(scene, settings) -> list:
    """The effect objects for a scene's [viscous_damping] ``settings`` (DampingSettings)."""
    return [ViscousDamping(f"viscous damping, a = -v / {settings.time_constant:g} s (settling)",
                           settings.time_constant)]
