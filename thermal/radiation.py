"""Radiation between a particle and what surrounds it (PHYSICS.md), for a dryer's burner zone:

    Q = eps_p sigma A_p (T_s^4 - T_p^4),   A_p = 4 pi r^2

Model: each particle (inside the optional ``radiation_region``) is a small grey sphere inside
a large isothermal grey enclosure at T_s - the local gas temperature (``radiation_to =
"gas"``: a flame / optically thick hot gas), an isothermal wall or body, or a given
temperature. For a small body in a large enclosure the grey-body exchange factor
1 / (1/eps_p + (A_p/A_s)(1/eps_s - 1)) tends to eps_p, so only the particle's emissivity
enters. Limits, said plainly: no view factors and no shadowing - a particle buried in the bed
radiates as freely as one on its surface, so restrict the exchange to where the bed surface
faces the source with ``radiation_region`` (and expect an overestimate inside it); no
particle-particle radiation; the gas neither absorbs nor is cooled by it (the plug-flow energy
balance carries convection only), and with a plug-flow gas a particle outside the gas's axial
span does not radiate (it has no gas temperature).

Stability of the explicit update: the exchange is linearised as the conductance
4 eps sigma A T^3 with T = max(T_p, T_s) (dQ/dT_p is 4 eps sigma A T_p^3; the larger T bounds
the secant too), added to the particle's sum of conductances.
"""
import taichi as ti

STEFAN_BOLTZMANN = 5.670374419e-8      # W/(m^2 K^4)


@ti.func
def exchange(emissivity, radius, surroundings_temperature, particle_temperature):
    """(Q W into the particle, linearised conductance W/K) for a sphere of ``radius`` m."""
    area = 4.0 * 3.141592653589793 * radius * radius
    k = emissivity * STEFAN_BOLTZMANN * area
    ts = surroundings_temperature
    tp = particle_temperature
    hot = ti.max(ts, tp)
    return k * (ts * ts * ts * ts - tp * tp * tp * tp), 4.0 * k * hot * hot * hot
