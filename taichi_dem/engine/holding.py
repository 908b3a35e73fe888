"""Held particles: the hooks through which an effect may hold particles still, or carry them
rigidly with a body's frame, between neighbour-list rebuilds (Newton's ``ACTIVE`` flag; the
"adaptive sparse contacts" of seed 000 and Lethe). The effect declares
``Effect.holds_particles`` and owns the flag ``particle_active`` (1: the particle moves and is
integrated; 0: held), which it refreshes after each rebuild (``Effect.after_rebuild``). The
step reads only the hooks below; a scene without such an effect gets constants that the
compiler folds away, so the step it compiles is the step without them.

    any              an effect holds particles (compile time)
    carried          held particles move with a body's frame, which bears their load
    moves(i)         ti.func: particle i is integrated (True) or held (False)
    release(i)       ti.func: mark an inserted particle as moving until the next judgement
    rigid_drift      ti.func (x, dt, t) -> x: a carried particle's position after the step, m
    rigid_velocity   ti.func (x, t) -> v: the frame's velocity there, m/s
    carried_load     ti.func (i, force, torque, acceleration): book what holds a carried
                     particle on the frame's body

The engine compiles its step twice where an effect can hold particles: with these hooks, and
with the constants of a scene without them (``idle``), and runs the second while
the holder's last judgement held nothing (``holds_any``): a flow where nothing is held then
runs the step of a scene without the effect. The hooks' reads and branches cost the 32k
chute 4 - 5 % even with every flag 1 and a run-time switch in front of them
(BENCHMARKS.md "Mobility where nothing freezes: the step without the hooks").
"""
import taichi as ti


class Holding:
    """The hooks of the enabled effect that holds particles, or their absence."""

    def __init__(self, effects, ctx, idle: bool = False):
        holders = [e for e in effects if e.holds_particles]
        if len(holders) > 1:
            raise ValueError("more than one effect holds particles: "
                             + ", ".join(e.name for e in holders))
        holder = holders[0] if holders else None
        self.holder = holder
        # ``idle``: the hooks of a step that runs while the holder holds nothing
        # (every flag 1): constants, as without a holder
        self.any = holder is not None and not idle
        self.carried = self.any and holder.carrier_body >= 0
        present = self.any
        flag = holder.particle_active if present else None

        @ti.func
        def moves(i):
            result = True
            if ti.static(present):
                result = flag[i] != 0
            return result

        @ti.func
        def release(i):
            if ti.static(present):
                flag[i] = 1

        self.moves, self.release = moves, release
        carried = self.carried
        self.rigid_drift = holder.make_rigid_drift(ctx) if carried else None
        self.rigid_velocity = holder.make_rigid_velocity(ctx) if carried else None
        self.carried_load = holder.make_carried_load(ctx) if carried else None

    def holds_any(self) -> bool:
        """Whether the holder's last judgement held any particle (its ``particles_held``,
        read from the device: a checkpoint restores it); False without a holder."""
        return self.any and int(self.holder.particles_held[0]) != 0
