"""Gas-gap conductance (issue 10 item 5, first check): the kernels' integrals against the model
integral evaluated by brute-force quadrature, for a sphere on a plate and two spheres, at
several gaps and overlaps (thermal/gas_gap.py).

The model: G = k_g Int 2 pi r dr / max(S, gap(r)) over the fluid lens (isothermal surfaces;
Rong & Horio 1999 / Musser 2011 for pairs, Morris et al. 2015 for a plane). The reference is
8-point Gauss-Legendre on 4000 panels graded towards the contact (converged to 1e-7: halving
the panels changes it by less). The issue asks for 1e-3; the sphere-plane closed form agrees
to round-off (1e-9 asserted), the 12-point sphere-sphere quadrature to 1e-4 (measured 9e-5 at worst, for a 10:1 pair;
asserted 1e-3).

Also checked: the conductance falls with the gap and is 0 beyond the lens; at contact a
30 mm ash sphere on a cold plate in air (k_g = 0.026) conducts ~0.01 W/K through the gas,
two orders more than through its Hertz spot (~1e-4 W/K at 1e-5 m overlap), which is why a
cooler without it does not cool (PHYSICS.md).
"""

import math

import numpy as np
import pytest
import taichi as ti

from taichi_dem.engine import backend
from taichi_dem.thermal import gas_gap


class _Owner:
    def _mark_stale(self, why):
        pass


@pytest.fixture(scope="module")
def kernels():
    owner = _Owner()
    backend.acquire(owner, "cpu", "f64")

    @ti.kernel
    def plane(radius: ti.types.ndarray(), distance: ti.types.ndarray(), lens: ti.f64,
              min_gap: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.plane_gap_integral(radius[k], distance[k], lens, min_gap)

    @ti.kernel
    def pair(ri: ti.types.ndarray(), rj: ti.types.ndarray(), distance: ti.types.ndarray(),
             lens: ti.f64, min_gap: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.pair_gap_integral(ri[k], rj[k], distance[k], lens, min_gap)

    def run_plane(radius, distance, lens, min_gap):
        r = np.asarray(radius, float)
        d = np.asarray(distance, float)
        out = np.zeros(len(d))
        plane(np.ascontiguousarray(np.broadcast_to(r, d.shape)), d, lens, min_gap, out)
        return out

    def run_pair(ri, rj, distance, lens, min_gap):
        d = np.asarray(distance, float)
        out = np.zeros(len(d))
        pair(np.ascontiguousarray(np.broadcast_to(np.asarray(ri, float), d.shape)),
             np.ascontiguousarray(np.broadcast_to(np.asarray(rj, float), d.shape)), d, lens,
             min_gap, out)
        return out

    return run_plane, run_pair


R = 0.015
# overlaps (negative distance - R) and gaps, relative to R
OFFSETS = np.array([-3e-3, -1e-3, -1e-4, -1e-5, 0.0, 1e-5, 1e-4, 1e-3, 1e-2, 5e-2, 0.15, 0.35])


@pytest.mark.parametrize("lens,min_gap", [(0.2, 1e-6), (0.4, 1e-6), (0.4, 1e-8)])
def test_sphere_on_plate_closed_form_equals_quadrature(kernels, lens, min_gap):
    run_plane, _ = kernels
    distance = R * (1.0 + OFFSETS)
    got = run_plane(R, distance, lens, min_gap)
    ref = np.array([gas_gap.plane_gap_integral_reference(R, d, lens, min_gap) for d in distance])
    for d, g, r in zip(distance, got, ref):
        print(f"  plane h/R = {d / R:.6f}: kernel {g:.9e} m, quadrature {r:.9e} m")
    inside = distance < R * (1.0 + lens)
    assert np.all(got[~inside] == 0.0)
    np.testing.assert_allclose(got[inside], ref[inside], rtol=1e-6)
    # closer is better conducting
    assert np.all(np.diff(got[OFFSETS >= 0]) < 0)


@pytest.mark.parametrize("ratio", [1.0, 0.5, 0.1])
@pytest.mark.parametrize("lens,min_gap", [(0.2, 1e-6), (0.4, 1e-6), (0.4, 1e-8)])
def test_two_spheres_quadrature_equals_reference(kernels, ratio, lens, min_gap):
    _, run_pair = kernels
    small = ratio * R
    distance = (R + small) + small * OFFSETS
    got = run_pair(R, small, distance, lens, min_gap)
    ref = np.array([gas_gap.pair_gap_integral_reference(R, small, d, lens, min_gap)
                    for d in distance])
    worst = np.max(np.abs(got - ref) / np.maximum(ref, 1e-300) * (ref > 0))
    print(f"\n  pair R_small/R = {ratio}, lens {lens}, S {min_gap:g}: worst relative "
          f"difference {worst:.2e}")
    assert np.all((got == 0.0) == (ref == 0.0))
    assert np.count_nonzero(ref) >= 8          # most of these gaps are inside the lens
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    # symmetric in the two radii
    np.testing.assert_allclose(run_pair(small, R, distance, lens, min_gap), got, rtol=1e-12)


def test_gas_gap_dominates_the_hertz_spot_for_ash_on_a_cold_wall(kernels):
    run_plane, _ = kernels
    k_gas, k_ash, k_steel = 0.026, 0.3, 45.0
    overlap = 1e-5
    g_gas = k_gas * run_plane(R, [R - overlap], 0.4, 1e-6)[0]
    spot = 4 * k_ash * k_steel / (k_ash + k_steel) * math.sqrt(R * overlap)
    print(f"\n  ash on steel: gas gap {g_gas:.4g} W/K, Hertz spot {spot:.4g} W/K")
    assert g_gas > 20 * spot


# ---------------------------------------------------- with the solid's own resistance
@pytest.fixture(scope="module")
def solid_kernels(kernels):
    @ti.kernel
    def plane(radius: ti.f64, distance: ti.types.ndarray(), lens: ti.f64, min_gap: ti.f64,
              g: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.plane_solid_gap_integral(radius, distance[k], lens, min_gap, g)

    @ti.kernel
    def pair(ri: ti.f64, rj: ti.f64, distance: ti.types.ndarray(), lens: ti.f64,
             min_gap: ti.f64, gi: ti.f64, gj: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.pair_solid_gap_integral(ri, rj, distance[k], lens, min_gap, gi, gj)

    return plane, pair


# k_g / k_s: steel, glass and ash in air
GAS_OVER_SOLID = [0.026 / 45.0, 0.026 / 1.0, 0.026 / 0.3]


@pytest.mark.parametrize("g", GAS_OVER_SOLID)
@pytest.mark.parametrize("lens,min_gap", [(0.2, 1e-6), (0.4, 1e-8)])
def test_solid_resistance_sphere_on_plate_equals_quadrature(solid_kernels, g, lens, min_gap):
    plane, _ = solid_kernels
    distance = R * (1.0 + OFFSETS)
    got = np.zeros(len(distance))
    plane(R, distance, lens, min_gap, g, got)
    ref = np.array([gas_gap.plane_solid_gap_integral_reference(R, d, lens, min_gap, g)
                    for d in distance])
    iso = np.array([gas_gap.plane_gap_integral_reference(R, d, lens, min_gap) for d in distance])
    worst = np.max(np.abs(got - ref) / np.maximum(ref, 1e-300) * (ref > 0))
    print(f"\n  plane k_g/k_s = {g:.3g}, lens {lens}: worst {worst:.2e}; at contact the solid "
          f"keeps {ref[4] / iso[4]:.3f} of the isothermal-surface conductance")
    assert np.all((got == 0.0) == (ref == 0.0))
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    # the solid's resistance only ever lowers the conductance
    assert np.all(ref <= iso * (1 + 1e-9))


@pytest.mark.parametrize("ratio", [1.0, 0.3])
@pytest.mark.parametrize("g", GAS_OVER_SOLID)
def test_solid_resistance_two_spheres_equals_quadrature(solid_kernels, ratio, g):
    _, pair = solid_kernels
    small = ratio * R
    distance = (R + small) + small * OFFSETS
    got = np.zeros(len(distance))
    pair(R, small, distance, 0.2, 1e-6, g, 2 * g, got)
    ref = np.array([gas_gap.pair_solid_gap_integral_reference(R, small, d, 0.2, 1e-6, g, 2 * g)
                    for d in distance])
    worst = np.max(np.abs(got - ref) / np.maximum(ref, 1e-300) * (ref > 0))
    print(f"\n  pair ratio {ratio}, k_g/k_s = {g:.3g}: worst relative difference {worst:.2e}")
    assert np.all((got == 0.0) == (ref == 0.0))
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    # symmetric under swapping the particles (with their conductivities)
    swapped = np.zeros(len(distance))
    pair(small, R, distance, 0.2, 1e-6, 2 * g, g, swapped)
    np.testing.assert_allclose(swapped, got, rtol=1e-12)


# ---------------------------------------------------- Voronoi cones (Cheng, Yu & Zulli 1999)
@pytest.fixture(scope="module")
def voronoi_kernels(kernels):
    @ti.kernel
    def plane(radius: ti.f64, distance: ti.types.ndarray(), lens: ti.f64, min_gap: ti.f64,
              g: ti.f64, porosity: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.plane_voronoi_gap_integral(radius, distance[k], lens, min_gap, g,
                                                        porosity)

    @ti.kernel
    def pair(ri: ti.f64, rj: ti.f64, distance: ti.types.ndarray(), lens: ti.f64,
             min_gap: ti.f64, gi: ti.f64, gj: ti.f64, porosity: ti.f64, out: ti.types.ndarray()):
        for k in range(out.shape[0]):
            out[k] = gas_gap.pair_voronoi_gap_integral(ri, rj, distance[k], lens, min_gap, gi,
                                                       gj, porosity)

    return plane, pair


@pytest.mark.parametrize("g", GAS_OVER_SOLID)
@pytest.mark.parametrize("porosity", [0.36, 0.45])
def test_voronoi_sphere_on_plate_equals_quadrature(voronoi_kernels, g, porosity):
    """The Voronoi-cone model's 16-point quadrature against the brute-force reference (1e-3;
    measured 9e-5 at worst), and below isothermal surfaces at contact (the solid's resistance
    only lowers it). Against the centre-plane series model it depends on the lens: the cones
    end at r_sf ~ 0.55 R where a lens of 0.4 R reaches 0.98 R."""
    plane, _ = voronoi_kernels
    distance = R * (1.0 + OFFSETS)
    got = np.zeros(len(distance))
    plane(R, distance, 0.4, 1e-6, g, porosity, got)
    ref = np.array([gas_gap.plane_voronoi_gap_integral_reference(R, d, 0.4, 1e-6, g, porosity)
                    for d in distance])
    worst = np.max(np.abs(got - ref) / np.maximum(ref, 1e-300) * (ref > 0))
    series = gas_gap.plane_solid_gap_integral_reference(R, R, 0.4, 1e-6, g)
    iso = gas_gap.plane_gap_integral_reference(R, R, 0.4, 1e-6)
    print(f"\n  plane k_g/k_s = {g:.3g}, porosity {porosity}: worst {worst:.2e}; at contact "
          f"{ref[4] / iso:.3f} of isothermal (centre-plane series {series / iso:.3f})")
    assert np.all((got == 0.0) == (ref == 0.0))
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    assert 0.0 < ref[4] < iso


@pytest.mark.parametrize("ratio", [1.0, 0.3])
@pytest.mark.parametrize("g", GAS_OVER_SOLID)
def test_voronoi_two_spheres_equals_quadrature(voronoi_kernels, ratio, g):
    _, pair = voronoi_kernels
    small = ratio * R
    distance = (R + small) + small * OFFSETS
    got = np.zeros(len(distance))
    pair(R, small, distance, 0.4, 1e-6, g, 2 * g, 0.4, got)
    ref = np.array([gas_gap.pair_voronoi_gap_integral_reference(R, small, d, 0.4, 1e-6, g,
                                                                2 * g, 0.4) for d in distance])
    worst = np.max(np.abs(got - ref) / np.maximum(ref, 1e-300) * (ref > 0))
    print(f"\n  voronoi pair ratio {ratio}, k_g/k_s = {g:.3g}: worst relative difference {worst:.2e}")
    assert np.all((got == 0.0) == (ref == 0.0))
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    swapped = np.zeros(len(distance))
    pair(small, R, distance, 0.4, 1e-6, 2 * g, g, 0.4, swapped)
    np.testing.assert_allclose(swapped, got, rtol=1e-12)


@pytest.mark.parametrize("offset", [-1e-3, 0.0, 1e-3, 0.1])
@pytest.mark.parametrize("porosity", [0.36, 0.45])
def test_voronoi_without_solid_resistance_is_the_isothermal_lens_to_the_cone(kernels, offset,
                                                                            porosity):
    """With k_s infinite (k_g/k_s = 0) the Voronoi-cone model is the isothermal-surface
    integral out to where the cone leaves the sphere, r_sf = R r_ij / sqrt(r_ij^2 + D^2),
    r_ij = 0.56 R (1 - e)^-1/3 (Cheng, Yu & Zulli; Yang, Zou & Yu): against the sphere-plane
    closed form (Morris et al.) with the lens set to end at r_sf, to 1e-6."""
    run_plane, _ = kernels
    d = R * (1.0 + offset)
    face = 0.56 * R * (1.0 - porosity) ** (-1.0 / 3.0)
    r_sf = R * face / math.sqrt(face ** 2 + d ** 2)
    lens = math.sqrt(r_sf ** 2 + d ** 2) / R - 1.0
    closed = run_plane(R, [d], lens, 1e-6)[0]
    cone = gas_gap.plane_voronoi_gap_integral_reference(R, d, 0.4, 1e-6, 0.0, porosity)
    assert closed > 0.0
    assert cone == pytest.approx(closed, rel=1e-6)
