"""The geometry of one contact, the same record for every contact kind.

A ``Contact`` holds what every contact effect reads (SI units):

    normal               unit vector from the partner (particle, plane, triangle) to particle i
    normal_overlap       m; > 0 touching, < 0 a gap (pairs within an effect's margin)
    arm_i, arm_j         m, centre to contact point (arm_j = 0 for a plane or triangle)
    v_rel                m/s, velocity of i relative to the partner at the contact point
    w_rel                rad/s, spin of i relative to the partner
    normal_acceleration  m/s^2, relative acceleration along the normal at the last step
    r_eff, m_eff         R* = r_i r_j/(r_i + r_j) (r_i on a wall), m* (0: no mechanics, a fixed
                         particle on a wall or two fixed particles)
    inertia_eff          kg m^2, 1/(1/I_i + 1/I_j) (I_i on a wall)
    rolling_inertia      kg m^2, 1/(1/(I_i + m_i r_i^2) + 1/(I_j + m_j r_j^2))
    radius_i, radius_j   m (radius_j = 0 for a plane or triangle: a flat partner)
    material_i, material_j  rows of the pair tables
    temperature_difference  K, T_partner - T_i (0 where the partner has no temperature)
    conducts             1 when the partner has a temperature (heat may flow), else 0

Values an enabled effect does not read are eliminated by the compiler.
"""
import taichi as ti

from .history import make_history_type

from ..effects import rolling


def contact_types(real, history_members=("tangential", "rolling")):
    """(Contact, Response, History) struct types in the simulation's precision.

    ``Response``: force on i (N), torques on i and on the partner about their centres (N m),
    heat into i (W), conductance (W/K), and the normal force (N) and normal stiffness (N/m)
    that later effects (rolling) read. ``History``: the values a contact carries from step to
    step, those the enabled effects keep (contacts/history.py: Hertz-Mindlin's tangential
    spring, m; EPSD's rolling spring, N m). ``Contact.particle``: particle i's index where a
    wall or body contact law needs its state (coarse_grained.py), else -1."""
    vec3 = ti.types.vector(3, real)
    contact = ti.types.struct(
        normal=vec3, normal_overlap=real, arm_i=real, arm_j=real, v_rel=vec3, w_rel=vec3,
        normal_acceleration=real, r_eff=real, m_eff=real, inertia_eff=real,
        rolling_inertia=real, radius_i=real, radius_j=real, material_i=ti.i32,
        material_j=ti.i32, temperature_difference=real, conducts=ti.i32, particle=ti.i32)
    response = ti.types.struct(force=vec3, torque_i=vec3, torque_j=vec3, heat=real,
                               conductance=real, normal_force=real, normal_stiffness=real)
    return contact, response, make_history_type(real, tuple(history_members))


def make_geometry(real, thermal: bool):
    """ti.funcs building a ``Contact``: (sphere_sphere, sphere_surface, sphere_sphere_gap,
    with_motion); sphere_sphere is sphere_sphere_gap completed by with_motion.

    sphere_sphere(d, dist_sq, particle i's and j's state ...) for two particles whose centres
    are ``d`` = x_i - x_j apart (minimum image, m); sphere_surface(...) for a particle on a
    surface (plane or triangle) at its nearest point, the surface moving at ``surface_velocity``
    (m/s, at the contact point) and spinning at ``surface_spin`` (rad/s)."""
    Contact, _, _ = contact_types(real)

    @ti.func
    def sphere_sphere_gap(d, distance_sq, ri, rj, mi, mj, ti_, tj_):
        """The geometry of two particles only (no motion): what heat effects read. A pair apart
        (within an effect's margin) needs no more: no mechanics acts across a gap, and a near
        pair is as common as a touching one in a bed with the gas gap on."""
        dist = ti.sqrt(distance_sq)
        normal_overlap = ri + rj - dist
        temperature_difference = 0.0 * ri
        if ti.static(thermal):
            temperature_difference = tj_ - ti_
        vec0 = ti.Vector([0.0, 0.0, 0.0]) * ri
        return Contact(
            normal=d / dist, normal_overlap=normal_overlap,       # normal from j to i
            arm_i=ri - 0.5 * normal_overlap, arm_j=rj - 0.5 * normal_overlap,  # to the contact point
            v_rel=vec0, w_rel=vec0, normal_acceleration=0.0 * ri,
            r_eff=ri * rj / (ri + rj), m_eff=0.0 * ri, inertia_eff=0.0 * ri,
            rolling_inertia=0.0 * ri, radius_i=ri, radius_j=rj, material_i=mi, material_j=mj,
            temperature_difference=temperature_difference, conducts=1, particle=-1)

    @ti.func
    def with_motion(c, vi, vj, wi, wj, ai, aj, inv_mi, inv_mj, inv_ii, inv_ij):
        """Contact ``c`` of two particles (sphere_sphere_gap) with their relative motion and
        effective masses filled in."""
        inverse_mass_sum = inv_mi + inv_mj
        m_eff = 0.0 * c.radius_i
        if inverse_mass_sum > 0.0:
            m_eff = 1.0 / inverse_mass_sum
        c.v_rel = vi - vj - (c.arm_i * wi + c.arm_j * wj).cross(c.normal)
        c.w_rel = wi - wj
        c.normal_acceleration = (ai - aj).dot(c.normal)
        c.m_eff = m_eff
        c.inertia_eff = 1.0 / (inv_ii + inv_ij)
        c.rolling_inertia = 1.0 / (rolling.rolling_inverse_inertia(inv_mi, inv_ii, c.radius_i)
                                   + rolling.rolling_inverse_inertia(inv_mj, inv_ij, c.radius_j))
        return c

    @ti.func
    def sphere_sphere(d, distance_sq, ri, rj, vi, vj, wi, wj, ai, aj, inv_mi, inv_mj,
                      inv_ii, inv_ij, mi, mj, ti_, tj_):
        return with_motion(sphere_sphere_gap(d, distance_sq, ri, rj, mi, mj, ti_, tj_),
                           vi, vj, wi, wj, ai, aj, inv_mi, inv_mj, inv_ii, inv_ij)

    @ti.func
    def sphere_surface(normal, normal_overlap, ri, vi, wi, ai, mass_i, inv_mi, inv_ii, mi, mj,
                       surface_velocity, surface_spin, temperature_difference, conducts):
        arm = ri - 0.5 * normal_overlap
        m_eff = 0.0 * ri
        if inv_mi > 0.0:
            m_eff = mass_i
        return Contact(
            normal=normal, normal_overlap=normal_overlap, arm_i=arm, arm_j=0.0 * ri,
            v_rel=vi - surface_velocity - arm * wi.cross(normal), w_rel=wi - surface_spin,
            normal_acceleration=ai.dot(normal), r_eff=ri, m_eff=m_eff,
            inertia_eff=1.0 / inv_ii,
            rolling_inertia=1.0 / rolling.rolling_inverse_inertia(inv_mi, inv_ii, ri),
            radius_i=ri, radius_j=0.0 * ri, material_i=mi, material_j=mj,
            temperature_difference=temperature_difference, conducts=conducts, particle=-1)

    return sphere_sphere, sphere_surface, sphere_sphere_gap, with_motion
