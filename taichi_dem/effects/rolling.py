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
def rolling_inverse_inertia(inverse_mass, inverse_inertia, radius):
    """1 / (I + m r^2), the inertia for rolling about the contact point (1/(kg m^2)); 0 for a
    fixed particle."""
    result = 0.0 * inverse_mass
    if inverse_mass > 0.0:
        result = inverse_inertia * inverse_mass / (inverse_mass + radius * radius * inverse_inertia)
    return result


@ti.func
def epsd(relative_spin, normal, normal_force, normal_stiffness, r_eff, rolling_friction,
         rolling_damping, rolling_inertia, rolling_history, dt):
    """EPSD rolling resistance (Ai et al. 2011, model C): a spring k_r = 2.25 S_n mu_r^2 R*^2
    on the relative rolling rotation, capped at mu_r R* F_n, plus a viscous torque
    -eta_r 2 sqrt(I_r k_r) w_r while the spring is below its cap (none once fully mobilised),
    the sum also capped at mu_r R* F_n.
    Without the viscous part a sphere rocks on its rolling spring for ever. ``rolling_inertia``
    is I_r = 1 / (1/(I_i + m_i r_i^2) + 1/(I_j + m_j r_j^2)), kg m^2. Returns (torque on this
    particle N m, updated spring torque N m)."""
    rolling_spin = relative_spin - relative_spin.dot(normal) * normal   # no twisting part
    stiffness = 2.25 * normal_stiffness * (rolling_friction * r_eff) ** 2
    spring = rotate_into_tangent_plane(rolling_history, normal) - stiffness * rolling_spin * dt
    limit = rolling_friction * r_eff * normal_force
    magnitude = spring.norm()
    torque = spring
    if magnitude > limit:
        spring *= limit / magnitude
        torque = spring
    else:
        torque = spring - rolling_damping * 2.0 * ti.sqrt(rolling_inertia * stiffness) * rolling_spin
        # the whole rolling resistance stays within mu_r R* F_n: at the onset of rolling the
        # spring is slack and the viscous torque alone would otherwise exceed it many times
        total = torque.norm()
        if total > limit:
            torque *= limit / total
    return torque, spring


from .base import Effect  # noqa: E402
from ..setup.pair_tables import ROLLING_MODEL_CODES  # noqa: E402


class _Rolling(Effect):
    stage = "contact"
    kinds = ("pair", "plane", "triangle")
    mechanical = True
    tables = ("rolling_friction", "rolling_model", "rolling_damping")
    model_code = -1

    def contact_func(self, ctx):
        rolling_friction, rolling_model, rolling_damping = (ctx.table[n] for n in self.tables)
        code = self.model_code
        epsd_model = self.name == "rolling_epsd"

        @ti.func
        def rolling_resistance(c, out, history, dt):
            mi, mj = c.material_i, c.material_j
            if rolling_friction[mi, mj] > 0.0 and rolling_model[mi, mj] == code:
                torque = c.w_rel * 0.0
                if ti.static(epsd_model):
                    torque, history.rolling = epsd(
                        c.w_rel, c.normal, out.normal_force, out.normal_stiffness, c.r_eff,
                        rolling_friction[mi, mj], rolling_damping[mi, mj], c.rolling_inertia,
                        history.rolling, dt)
                else:
                    torque = constant_torque(c.w_rel, out.normal_force, c.r_eff,
                                             rolling_friction[mi, mj], c.inertia_eff, dt)
                out.torque_i += torque
                out.torque_j -= torque
            return out, history

        return rolling_resistance


class RollingConstantTorque(_Rolling):
    """Constant directional torque (EDEM type A) on pairs whose interaction asks for it."""
    name = "rolling_constant_torque"
    model_code = ROLLING_MODEL_CODES["constant_torque"]


class RollingEPSD(_Rolling):
    """EPSD rolling spring (Ai et al. 2011 model C) on pairs whose interaction asks for it."""
    name = "rolling_epsd"
    model_code = ROLLING_MODEL_CODES["epsd"]
    contact_fields = {"rolling_history": (True, "real")}
