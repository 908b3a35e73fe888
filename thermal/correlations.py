"""Closed-form correlations to check the DEM's heat transfer against (plain numpy, SI units).

Wall-to-bed heat transfer in a rotating drum (rolling bed, no flights): the penetration model
of Schlünder and Mollekopf (E.-U. Schlünder, Chem. Eng. Process. 18 (1984) 31-53; E.-U.
Schlünder and N. Mollekopf, Chem. Eng. Process. 18 (1984) 93-111; the forms collected in the VDI
Heat Atlas, 2nd ed. 2010, chapter M7 "Heat transfer to mechanically agitated beds", and used for
rotary drums by Herz, Specht et al. and by Komossa et al., Powder Technol. 286 (2015) 722).
Written here from those standard forms (the papers themselves were not at hand: see
docs/verification/drum_wall_heat.md for what was and was not checked).

A wall element under the bed first sees the particles of the first layer (a contact
resistance 1/alpha_WS), then, for the time t_c it stays covered, heat penetrates the bed as
into a semi-infinite body of the bed's effective properties. In series (the simple form)::

    1/alpha = 1/alpha_WS + 1/alpha_bed                                          [W/(m^2 K)]

    alpha_bed = 2 sqrt(rho_b c_b k_b / (pi t_c))      the mean over 0..t_c of the penetration
                                                      coefficient sqrt(k rho c / (pi t))
    t_c       = (2 eps) / omega                       2 eps the wetted angle, omega the speed

    alpha_WS  = phi_A alpha_WP + (1 - phi_A) 2 k_g / (sqrt(2) d + 2 (l + delta)) + alpha_rad
    alpha_WP  = (4 k_g / d) [(1 + 2 (l + delta)/d) ln(1 + d / (2 (l + delta))) - 1]
    alpha_rad = 4 C_WS T_m^3,  C_WS = sigma / (1/eps_W + 1/eps_bed - 1)

alpha_WP is the gas conductance of one isothermal sphere touching an isothermal plane, with the
gap everywhere widened by l + delta, per projected area pi d^2/4 (integrate k_g 2 pi r dr /
(R - sqrt(R^2 - r^2) + l + delta) over 0 < r < R); phi_A ~ 0.8 the surface coverage of the
wall by the first layer; delta the surface roughness; l the modified mean free path of the gas::

    l = 2 (2 - gamma)/gamma * Lambda,   Lambda = sqrt(2 pi R_u T / M) k_g / (p (2 c_p - R_u / M))
    log10(1/gamma - 1) = 0.6 - (1000 K / T + 1) / C_A,   C_A = 2.8 for air

(gamma the accommodation coefficient). A more exact series combination solves the
semi-infinite body with a surface conductance alpha_WS (Carslaw & Jaeger sec. 2.7): the flux
alpha_WS dT exp(b^2) erfc(b), b = alpha_WS sqrt(t / (k rho c)), averaged over t_c
(:func:`penetration_with_contact_resistance`); it lies above the simple form, by at most
5.0 % (where alpha_bed = 0.84 alpha_WS).
"""
from __future__ import annotations

import math


def erfcx(x: float) -> float:
    """exp(x^2) erfc(x) for x >= 0 without overflow (math.erfc keeps its relative accuracy in
    the tail; beyond x = 25 the asymptotic series, relative error below 1e-10)."""
    if x < 25.0:
        return math.exp(x * x) * math.erfc(x)
    inv = 1.0 / (x * x)
    return (1.0 - 0.5 * inv + 0.75 * inv * inv - 1.875 * inv ** 3) / (x * math.sqrt(math.pi))


SIGMA = 5.670374419e-8        # W/(m^2 K^4)
R_UNIVERSAL = 8.314462618     # J/(mol K)


def wetted_angle_from_fill(fill: float) -> float:
    """The wetted (central) angle 2 eps (rad) of a drum's shell under a flat bed occupying the
    fraction ``fill`` of the cross-section: 2 eps - sin(2 eps) = 2 pi fill (circular segment)."""
    if not 0.0 < fill < 1.0:
        raise ValueError(f"fill degree must be in (0, 1), got {fill}")
    target = 2.0 * math.pi * fill
    x = math.pi                               # Newton on f(x) = x - sin x - target, monotone
    for _ in range(60):
        f = x - math.sin(x) - target
        x -= f / max(1.0 - math.cos(x), 1e-12)
        x = min(max(x, 1e-9), 2.0 * math.pi)
    return x


def contact_time(wetted_angle: float, rpm: float) -> float:
    """t_c = 2 eps / omega (s): how long a wall element stays under the bed, ``wetted_angle``
    in rad, the speed in revolutions per minute."""
    return wetted_angle / (rpm * 2.0 * math.pi / 60.0)


def accommodation_coefficient(temperature: float, c_a: float = 2.8) -> float:
    """Thermal accommodation coefficient gamma of a gas on a surface (VDI Heat Atlas M7; C_A =
    2.8 for air): log10(1/gamma - 1) = 0.6 - (1000 K / T + 1) / C_A."""
    return 1.0 / (1.0 + 10.0 ** (0.6 - (1000.0 / temperature + 1.0) / c_a))


def modified_mean_free_path(temperature: float, pressure: float = 101325.0,
                            k_gas: float = 0.0262, molar_mass: float = 0.02897,
                            heat_capacity: float = 1007.0, c_a: float = 2.8) -> float:
    """Schlünder's modified mean free path l = 2 (2 - gamma)/gamma Lambda (m), Lambda =
    sqrt(2 pi R T / M) k_g / (p (2 c_p - R/M)): T in K, p in Pa, k_g in W/(m K), M in kg/mol,
    c_p in J/(kg K). Air at 330 K, 1 atm: about 0.3 um."""
    r_specific = R_UNIVERSAL / molar_mass
    free_path = (math.sqrt(2.0 * math.pi * r_specific * temperature) * k_gas
                 / (pressure * (2.0 * heat_capacity - r_specific)))
    gamma = accommodation_coefficient(temperature, c_a)
    return 2.0 * (2.0 - gamma) / gamma * free_path


def wall_particle_coefficient(diameter: float, k_gas: float, gap: float) -> float:
    """alpha_WP (W/(m^2 K)): one isothermal sphere of ``diameter`` (m) touching an isothermal
    wall through a gas of conductivity ``k_gas``, every local gap widened by ``gap`` = l +
    delta (m); per projected area of the sphere:
    (4 k_g / d) [(1 + 2 gap / d) ln(1 + d / (2 gap)) - 1]."""
    b = 2.0 * gap / diameter
    return 4.0 * k_gas / diameter * ((1.0 + b) * math.log1p(1.0 / b) - 1.0)


def radiation_coefficient(temperature: float, emissivity_wall: float,
                          emissivity_bed: float) -> float:
    """alpha_rad = 4 C_WS T^3 (W/(m^2 K)), C_WS = sigma / (1/eps_W + 1/eps_bed - 1), T the
    mean of the wall and bed temperatures (K); 0 if either emissivity is 0."""
    if emissivity_wall <= 0.0 or emissivity_bed <= 0.0:
        return 0.0
    c = SIGMA / (1.0 / emissivity_wall + 1.0 / emissivity_bed - 1.0)
    return 4.0 * c * temperature ** 3


def wall_contact_coefficient(diameter: float, k_gas: float, temperature: float, *,
                             roughness: float = 0.0, coverage: float = 0.8,
                             emissivity_wall: float = 0.0, emissivity_bed: float = 0.0,
                             pressure: float = 101325.0, free_path: float | None = None) -> dict:
    """Schlünder's first-layer (wall-to-particle) coefficient alpha_WS (W/(m^2 K)) and its
    parts: phi_A alpha_WP + (1 - phi_A) 2 k_g / (sqrt(2) d + 2 (l + delta)) + alpha_rad.

    diameter d (m); k_gas (W/(m K)); temperature (K) for the mean free path and radiation;
    roughness delta (m); coverage phi_A; emissivities (0 = no radiation, as in a DEM without
    it); free_path l (m) if given, else :func:`modified_mean_free_path` of air at p (Pa)."""
    l = modified_mean_free_path(temperature, pressure, k_gas) if free_path is None else free_path
    gap = l + roughness
    wp = wall_particle_coefficient(diameter, k_gas, gap)
    uncovered = 2.0 * k_gas / (math.sqrt(2.0) * diameter + 2.0 * gap)
    rad = radiation_coefficient(temperature, emissivity_wall, emissivity_bed)
    total = coverage * wp + (1.0 - coverage) * uncovered + rad
    return {"alpha_ws": total, "alpha_wp": wp, "uncovered": uncovered, "radiation": rad,
            "free_path": l}


def penetration_coefficient(density: float, heat_capacity: float, conductivity: float,
                            time: float) -> float:
    """alpha_bed = 2 sqrt(rho_b c_b k_b / (pi t_c)) (W/(m^2 K)): the mean over a contact of
    duration ``time`` (s) of the coefficient of a semi-infinite body of the bed's density
    (kg/m^3, bulk), heat capacity (J/(kg K)) and effective conductivity (W/(m K)) whose
    surface is suddenly held at another temperature."""
    return 2.0 * math.sqrt(density * heat_capacity * conductivity / (math.pi * time))


def penetration_with_contact_resistance(alpha_ws: float, density: float, heat_capacity: float,
                                        conductivity: float, time: float) -> float:
    """The mean coefficient (W/(m^2 K)) over ``time`` of a semi-infinite body behind a surface
    conductance ``alpha_ws`` (exact series, Carslaw & Jaeger 2.7): with e = rho c k and
    b = alpha_ws sqrt(t_c / e),  alpha = (e / (alpha_ws t_c)) [exp(b^2) erfc(b) - 1 + 2 b /
    sqrt(pi)]. Tends to alpha_ws as t_c -> 0 and to 2 sqrt(e / (pi t_c)) as t_c -> inf."""
    e = density * heat_capacity * conductivity
    b = alpha_ws * math.sqrt(time / e)
    if b < 1e-4:                              # series: alpha_ws (1 - 4 b / (3 sqrt(pi)) + ...)
        return alpha_ws * (1.0 - 4.0 * b / (3.0 * math.sqrt(math.pi)) + b * b / 2.0)
    return e / (alpha_ws * time) * (float(erfcx(b)) - 1.0 + 2.0 * b / math.sqrt(math.pi))


def zehner_schlunder(k_solid: float, k_gas: float, porosity: float, free_path: float = 0.0,
                     diameter: float = 1.0) -> float:
    """Zehner-Bauer-Schlünder effective conductivity (W/(m K)) of a packed bed of spheres
    without radiation or flattening (VDI Heat Atlas D6.3), with the Smoluchowski effect when
    ``free_path`` l (m, Schlünder's modified mean free path) and the particle ``diameter`` d (m)
    are given: kappa_G = k_G / k_g = 1 / (1 + l / d)::

        B = 1.25 ((1 - eps) / eps)^(10/9),  kappa = k_s / k_g
        N = (1 / kappa_G) (1 - B kappa_G / kappa) - B (1 / kappa_G - 1)
        k_c = (2 / N) [B (kappa - 1) / (N^2 kappa_G kappa) ln(kappa / (B (kappa_G + (1 -
              kappa_G) kappa))) - (B + 1) / 2 - (B - 1) / (N kappa_G)]
        k_eff = k_g [(1 - sqrt(1 - eps)) eps / (eps - 1 + 1 / kappa_G) + sqrt(1 - eps) k_c]

    (radiation and flattening set to 0 in the VDI form; written from that form and checked
    against an independent implementation of it; l = 0 gives the plain model: N = 1 - B /
    kappa, the void term (1 - sqrt(1 - eps)))."""
    lam = k_solid / k_gas
    b = 1.25 * ((1.0 - porosity) / porosity) ** (10.0 / 9.0)
    kg = 1.0 / (1.0 + free_path / diameter)
    n = (1.0 - b * kg / lam) / kg - b * (1.0 / kg - 1.0)
    k_c = 2.0 / n * (b * (lam - 1.0) / (n * n * kg * lam)
                     * math.log(lam / (b * (kg + (1.0 - kg) * lam)))
                     - (b + 1.0) / 2.0 - (b - 1.0) / (n * kg))
    root = math.sqrt(1.0 - porosity)
    return k_gas * ((1.0 - root) * porosity / (porosity - 1.0 + 1.0 / kg) + root * k_c)


def schlunder_mollekopf(*, rpm: float, wetted_angle: float, diameter: float, k_gas: float,
                        bed_density: float, heat_capacity: float, bed_conductivity: float,
                        temperature: float, roughness: float = 0.0, coverage: float = 0.8,
                        emissivity_wall: float = 0.0, emissivity_bed: float = 0.0,
                        free_path: float | None = None) -> dict:
    """Wall-to-bed coefficient of a rolling drum bed, 1/alpha = 1/alpha_WS + 1/alpha_bed.

    rpm (1/min); wetted_angle 2 eps (rad); diameter (m); k_gas, bed_conductivity (W/(m K));
    bed_density (kg/m^3, bulk); heat_capacity (J/(kg K)); temperature (K) for the gas's mean
    free path and radiation; the rest as :func:`wall_contact_coefficient`. Returns alpha
    (the simple series), alpha_exact (:func:`penetration_with_contact_resistance`), alpha_ws,
    alpha_bed, t_c and the contact parts."""
    t_c = contact_time(wetted_angle, rpm)
    ws = wall_contact_coefficient(diameter, k_gas, temperature, roughness=roughness,
                                  coverage=coverage, emissivity_wall=emissivity_wall,
                                  emissivity_bed=emissivity_bed, free_path=free_path)
    bed = penetration_coefficient(bed_density, heat_capacity, bed_conductivity, t_c)
    alpha = 1.0 / (1.0 / ws["alpha_ws"] + 1.0 / bed)
    exact = penetration_with_contact_resistance(ws["alpha_ws"], bed_density, heat_capacity,
                                                bed_conductivity, t_c)
    return dict(ws, alpha=alpha, alpha_exact=exact, alpha_bed=bed, contact_time=t_c)


__all__ = ["wetted_angle_from_fill", "contact_time", "accommodation_coefficient",
           "modified_mean_free_path", "wall_particle_coefficient", "radiation_coefficient",
           "wall_contact_coefficient", "penetration_coefficient",
           "penetration_with_contact_resistance", "schlunder_mollekopf", "zehner_schlunder"]
