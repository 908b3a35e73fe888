"""The flights' geometric model (app/flights.py) against closed forms, and the DEM's flight
loads read from positions."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from taichi_dem.app import flights as fl

R, H, LIP = 0.5, 0.08, 0.04
L_FLIGHT = fl.Flights(8, R, H, LIP)


def test_schofield_glikin_at_rest_is_the_friction_angle_and_grows_with_froude():
    mu = 0.6
    assert float(fl.kinetic_angle(0.7, mu, 0.0)) == pytest.approx(math.atan(mu), abs=1e-12)
    # at delta = 0 the closed form: tan g = (mu + Fr) / (1 - Fr mu)
    fr = 0.05
    assert math.tan(float(fl.kinetic_angle(0.0, mu, fr))) == pytest.approx(
        (mu + fr) / (1 - fr * mu), rel=1e-12)


def test_at_nine_o_clock_the_load_is_the_integral_under_the_surface():
    """The leg horizontal: the solids fill from the lip (x = R - H) to the shell, up to the
    surface rising from the tip (height LIP) at gamma, or the shell where that is lower."""
    gamma = math.radians(32.0)

    def top(x):
        return min(LIP + (x - (R - H)) * math.tan(gamma), math.sqrt(R * R - x * x))
    exact = quad(top, R - H, R, limit=200)[0]
    # the disc is a polygon of 2048 sides: its area falls short by ~ (2 pi / n)^2 / 6 of
    # the circle's near the shell; 1e-4 covers it here
    assert fl.holdup_area(L_FLIGHT, 0.0, gamma) == pytest.approx(exact, rel=1e-4)


def test_at_the_top_the_lip_holds_a_triangle_and_the_flight_empties_at_90_plus_gamma():
    """At 90 deg the lip is a floor under the solids: the triangle between it, the leg and
    the surface, LIP^2 tan(gamma) / 2. Past it the lip tilts down towards its tip; the flight
    is empty once the lip's tilt reaches gamma (Fr = 0: gamma constant)."""
    gamma = math.radians(30.0)
    assert fl.holdup_area(L_FLIGHT, math.pi / 2, gamma) == pytest.approx(
        0.5 * LIP ** 2 * math.tan(gamma), rel=1e-9)
    empty = fl.final_discharge_angle(L_FLIGHT, math.tan(gamma), 0.0)
    assert math.degrees(empty) == pytest.approx(120.0, abs=1e-3)


def test_the_model_profile_falls_to_zero_and_stays_there():
    angles = np.radians(np.arange(0.0, 180.0, 5.0))
    held = fl.model_profile(L_FLIGHT, angles, 0.55, 0.03)
    assert np.all(np.diff(held) <= 1e-12) and held[0] > 0.0
    assert held[-1] == 0.0


def test_a_straight_flight_empties_when_its_plate_tilts_past_gamma():
    """A radial plate without a lip: from its tip the plate rises towards the shell at delta,
    the surface at gamma; solids lie between them while gamma > delta (Fr = 0)."""
    straight = fl.Flights(8, R, H)
    gamma = math.radians(30.0)
    assert math.degrees(fl.final_discharge_angle(straight, math.tan(gamma), 0.0)) == \
        pytest.approx(30.0, abs=1e-3)
    assert fl.holdup_area(straight, math.radians(20.0), gamma) > 0.0


def test_flight_loads_count_what_lies_between_leg_lip_and_tip():
    """Particles placed by hand around a flight at 30 deg: in its pocket, near the shell ahead
    of the lip (still on the rising side of the tip), inward of its lip's line, behind its leg
    (where no flight holds it: below the lip's line of the flight before), and airborne."""
    delta = math.radians(30.0)
    e_r = np.array([math.cos(delta), math.sin(delta)])
    e_t = np.array([-math.sin(delta), math.cos(delta)])
    points = np.array([
        (R - 0.03) * e_r + 0.02 * e_t,
        (R - 0.01) * e_r + 0.05 * e_t,
        (R - H - 0.03) * e_r + 0.02 * e_t,
        (R - 0.03) * e_r - 0.02 * e_t,
        (R - 0.03) * e_r + 0.01 * e_t,
    ])
    mass = np.array([1.0, 2.0, 4.0, 8.0, 16.0])
    held = np.array([True, True, True, True, False])
    angles, loads = fl.flight_loads(points, mass, held, fl.Flights(8, R, H, LIP, phase=delta), 0.0)
    assert math.degrees(angles[0]) == pytest.approx(30.0)
    assert loads[0] == pytest.approx(3.0)
    assert loads.sum() == pytest.approx(3.0)
    # the drum turned by 45 deg: the same particles now lie ahead of the flight before
    angles, loads = fl.flight_loads(points, mass, held, fl.Flights(8, R, H, LIP, phase=delta),
                                    -math.pi / 4)
    assert math.degrees(angles[1]) == pytest.approx(30.0) and loads[1] == pytest.approx(3.0)


def test_flights_of_reads_a_drum_mesh_table():
    mesh = {"builder": "drum", "radius": 0.5, "length": 0.24, "flights": 8,
            "flight_height": 0.08, "flight_shape": "L", "flight_lip": 0.04,
            "flight_phase_deg": 10.0}
    f = fl.flights_of(mesh, +1.0)
    assert (f.count, f.radius, f.height, f.lip) == (8, 0.5, 0.08, 0.04)
    assert math.degrees(f.phase) == pytest.approx(10.0)
    # turning the other way the lip trails: the model does not hold
    assert fl.flights_of(mesh, -1.0) is None
    mirrored = fl.flights_of({**mesh, "flight_lip_side": "trailing"}, -1.0)
    assert math.degrees(mirrored.phase) == pytest.approx(170.0)
    assert fl.flights_of({**mesh, "flights": 0}, 1.0) is None
    assert fl.flights_of({"builder": "paddle_shaft"}, 1.0) is None
    assert fl.flights_of({**mesh, "radius": "500 mm"}, 1.0).radius == pytest.approx(0.5)
