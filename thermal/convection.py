"""Convection to a gas (PHYSICS.md): Q = h A (T_g - T_p), h = k_g Nu / d, A = pi d^2.

Nusselt correlations: Ranz-Marshall, Nu = 2 + 0.6 Re^(1/2) Pr^(1/3) (a single sphere, Re <
200 in its original fit); Gunn (1978) for packed and fluidised beds of voidage eps,
Nu = (7 - 10 eps + 5 eps^2)(1 + 0.7 Re^0.2 Pr^(1/3)) + (1.33 - 2.4 eps + 1.2 eps^2) Re^0.7 Pr^(1/3).
Re = rho_g d |u_g - v_p| / mu_g, Pr = c_g mu_g / k_g.
"""
import taichi as ti


@ti.func
def nusselt_ranz_marshall(reynolds, prandtl_cube_root):
    return 2.0 + 0.6 * ti.sqrt(reynolds) * prandtl_cube_root


@ti.func
def nusselt_gunn(reynolds, prandtl_cube_root, porosity):
    eps = porosity
    return ((7.0 - 10.0 * eps + 5.0 * eps * eps) * (1.0 + 0.7 * reynolds ** 0.2 * prandtl_cube_root)
            + (1.33 - 2.4 * eps + 1.2 * eps * eps) * reynolds ** 0.7 * prandtl_cube_root)


@ti.func
def convective_conductance(gas_conductivity, nusselt, diameter):
    """h A, W/K, of a sphere of ``diameter`` m."""
    return gas_conductivity * nusselt / diameter * (3.141592653589793 * diameter * diameter)
