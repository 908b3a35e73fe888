"""Hertz-Mindlin (no slip) contact with tangential history and the Coulomb limit.

PHYSICS.md "Hertz-Mindlin"; EDEM's default model (seed 001, eqs. 5-11):

    F_n   = 4/3 E* sqrt(R*) d_n^(3/2)            S_n = 2 E* sqrt(R* d_n)
    F_n^d = -zeta sqrt(S_n m*) v_n                S_t = 8 G* sqrt(R* d_n)
    F_t   = -S_t d_t - zeta sqrt(S_t m*) v_t,     |F_t| <= mu_s F_n,total

The total normal force is clamped at zero (no adhesion); zeta is the damping ratio that makes
the clamped contact rebound with the user's restitution (restitution.py), so the restitution
set is the restitution achieved and the Coulomb cap on the clamped total makes the tangential
impulse mu_s times the normal impulse in gross sliding, as rigid-body theory has it.
"""
import taichi as ti


@ti.func
def rotate_into_tangent_plane(history, normal):
    """Project a stored tangential vector onto the plane normal to ``normal``, keeping its
    length: the contact frame has rotated since the last step (LIGGGHTS-style)."""
    projected = history - history.dot(normal) * normal
    projected_sq = projected.dot(projected)
    result = projected * 0.0
    if projected_sq > 0.0:
        result = projected * ti.sqrt(history.dot(history) / projected_sq)
    return result


@ti.func
def contact_force(normal, normal_overlap, r_eff, m_eff, v_rel, normal_acceleration,
                  tangential_history, youngs_eff, shear_eff, damping, friction, dt,
                  tangential_damping_ratio):
    """One Hertz-Mindlin contact. ``normal`` is the unit vector from the partner to this
    particle, ``v_rel`` the velocity of this particle relative to the partner at the contact
    point (m/s, at the half step), ``normal_acceleration`` the relative acceleration along
    ``normal`` at the last step (m/s^2). Returns (normal force magnitude N (clamped total, >= 0), tangential force on
    this particle N, updated tangential displacement m, normal stiffness S_n N/m)."""
    contact_stiffness_root = ti.sqrt(r_eff * normal_overlap)           # sqrt(R* d_n)
    normal_stiffness = 2.0 * youngs_eff * contact_stiffness_root        # S_n
    tangential_stiffness = 8.0 * shear_eff * contact_stiffness_root     # S_t
    normal_speed = v_rel.dot(normal)                                    # < 0 approaching
    # velocity Verlet knows v at the half step only; damping with it lags the force by dt/2
    # and makes the achieved restitution first-order wrong in dt (-0.23/N at e = 0.1, N steps
    # per contact). Predicting v_n at the full step, v + a dt/2, makes it second order.
    predicted_normal_speed = normal_speed + 0.5 * dt * normal_acceleration
    elastic_normal = 4.0 / 3.0 * youngs_eff * contact_stiffness_root * normal_overlap
    normal_damping = damping * ti.sqrt(normal_stiffness * m_eff)       # zeta sqrt(S_n m*)
    normal_force = elastic_normal - normal_damping * predicted_normal_speed
    normal_force = ti.max(normal_force, 0.0)

    tangential_velocity = v_rel - normal_speed * normal
    displacement = rotate_into_tangent_plane(tangential_history, normal) + tangential_velocity * dt
    # zeta sqrt(S_t m*) = zeta sqrt(S_n m*) sqrt(4 G*/E*), the last factor a pair table:
    # no square root or division more per contact
    tangential_damping = normal_damping * tangential_damping_ratio
    tangential_force = -tangential_stiffness * displacement - tangential_damping * tangential_velocity
    limit = friction * normal_force
    magnitude_sq = tangential_force.dot(tangential_force)
    if magnitude_sq > limit * limit:
        # sliding: the force sits on the Coulomb cone and the spring is reset to hold it there
        tangential_force *= limit / ti.sqrt(magnitude_sq)
        displacement = -tangential_force / tangential_stiffness
    return normal_force, tangential_force, displacement, normal_stiffness


from .base import Effect  # noqa: E402  (the effect object below uses the law above)


class HertzMindlin(Effect):
    """Hertz-Mindlin no-slip contact on every kind of contact (pairs, planes, triangles)."""

    name = "hertz_mindlin"
    stage = "contact"
    kinds = ("pair", "plane", "triangle")
    mechanical = True
    contact_fields = {"tangential_history": (True, "real")}
    tables = ("youngs_eff", "shear_eff", "damping", "friction", "tangential_damping_ratio")

    def table_values(self, scene, tables) -> dict:
        """The pair tables, and sqrt(4 G*/E*): sqrt(S_t / S_n), which turns the normal
        damping coefficient into the tangential one (dimensionless)."""
        import numpy as np
        values = {name: getattr(tables, name) for name in self.tables[:4]}
        # (0, not 0/0, for a pair of materials that never meet: no interaction, zero tables)
        ratio = np.divide(4.0 * tables.shear_eff, tables.youngs_eff,
                          out=np.zeros_like(tables.youngs_eff), where=tables.youngs_eff > 0.0)
        values["tangential_damping_ratio"] = np.sqrt(ratio)
        return values

    def contact_func(self, ctx):
        youngs_eff, shear_eff, damping, friction, tangential_damping_ratio = (
            ctx.table[n] for n in self.tables)

        @ti.func
        def hertz_mindlin(c, out, history, dt):
            mi, mj = c.material_i, c.material_j
            fn, ft, tangential, sn = contact_force(
                c.normal, c.normal_overlap, c.r_eff, c.m_eff, c.v_rel, c.normal_acceleration,
                history.tangential, youngs_eff[mi, mj], shear_eff[mi, mj], damping[mi, mj],
                friction[mi, mj], dt, tangential_damping_ratio[mi, mj])
            out.force = fn * c.normal + ft
            lever = c.normal.cross(ft)
            out.torque_i = -c.arm_i * lever
            out.torque_j = -c.arm_j * lever
            out.normal_force = fn
            out.normal_stiffness = sn
            history.tangential = tangential
            return out, history

        return hertz_mindlin
