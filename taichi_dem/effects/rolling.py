"""Rolling friction (PHYSICS.md): the constant directional torque model (EDEM type A / CDT)
and the elastic-plastic spring-dashpot model EPSD (Ai, Chen, Rotter & Ooi 2011, without the
viscous part).

Both use the rolling radius R* (the effective radius; R for a sphere on a wall), so the
torques on the two partners are equal and opposite, as in Ai et al. and LIGGGHTS.
"""
import taichi as ti

from .hertz_mindlin import rotate_into_tangent_plane


@ti.func
def constant_torque(relative_spin, normal_force, r_eff, rolling_friction, inertia_eff, dt):
    """tau = -mu_r F_n R* w_rel/|w_rel| on this particle (N m), limited so that it cannot
    reverse the relative spin within one step (otherwise a resting sphere chatters)."""
    spin = relative_spin.norm()
    torque = relative_spin * 0.0
    if spin > 0.0:
        magnitude = ti.min(rolling_friction * normal_force * r_eff, spin * inertia_eff / dt)
        torque = -magnitude / spin * relative_spin
    return torque


@ti.func
def epsd(relative_spin, normal, normal_force, normal_stiffness, r_eff, rolling_friction,
         rolling_history, dt):
    """EPSD rolling resistance: a spring k_r = 2.25 S_n mu_r^2 R*^2 on the relative rolling
    rotation, capped at mu_r R* F_n. Returns (torque on this particle N m, updated spring
    torque history N m)."""
    rolling_spin = relative_spin - relative_spin.dot(normal) * normal   # no twisting part
    stiffness = 2.25 * normal_stiffness * (rolling_friction * r_eff) ** 2
    torque = rotate_into_tangent_plane(rolling_history, normal) - stiffness * rolling_spin * dt
    limit = rolling_friction * r_eff * normal_force
    magnitude = torque.norm()
    if magnitude > limit:
        torque *= limit / magnitude
    return torque, torque
