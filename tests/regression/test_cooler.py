"""Regression: the scaled paddle cooler (demos/paddle_cooler.toml) to 12 s, seed 1.

Pinned from reference runs (tests/regression/cooler_reference.py, seeds 1-4, f32, CPU, with the
gas gap between particles on, as the demo now has it, 2026-12-01):
    seed 1: axial torque -8.587 N m, median residence 3.073 s (920 particles)
    seed 2: axial torque -8.951 N m, median residence 2.859 s (921 particles)
    seed 3: axial torque -9.263 N m, median residence 2.885 s (891 particles)
    seed 4: axial torque -9.125 N m, median residence 3.021 s (903 particles)
    torque mean -8.982 std 0.292; residence mean 2.960 std 0.104
The test runs seed 1 and accepts the mean of the seeds +- 3 standard deviations of that
scatter (torque +- 0.88 N m, residence +- 0.31 s): a change of the contact law, the mesh
contacts, the factory or the outlet that moves either beyond the scatter of seeds fails.
(The previous pins, seeds 1-3 before the effect refactor: torque -8.958 +- 0.543, residence
2.725 +- 0.107. The mechanics did not change: the refactored step matches the old one to 4e-9
m after 0.15 s on one thread in f64, and the gas gap's near pairs change the cell grid, so the
particles' order and the chaotic trajectories, by as little (2e-9); seed 1 moved from 2.79 to
3.07 s, within the new scatter of seeds, and the old pins' three seeds had understated it.)
(The torque is negative: the particles resist the shaft's positive rotation.)

The shell's heat flow (mean over [T0, UNTIL]) with the ash coarse-grained for 100 um particles
(issue 10: [materials.ash] coarse_grained, thermal/coarse_grained.py), seeds 1-4, 2026-12-02:
    13462, 13584, 13548, 13542 W: mean 13534, std 51.6
pinned first as mean +- 3 std (+- 155 W, 1.1 %; now wider, below): a change of the wall heat
law, the contact ages, the bed's mixing at the shell or the shell's conductance that moves it beyond the seeds' scatter
fails. (The same runs' torque and residence, -8.953 +- 0.424 N m and 2.987 +- 0.113 s, agree
with the pins above; seed 1 read -8.563 N m and 2.923 s.)

The scatter of seeds understates the torque's and the shell heat flow's (2026-12-03): seed 1
run 11 times with round-off perturbations (the normal damping scaled by 1 +- k 1e-7, k = 1 - 4,
a scratch edit of effects/hertz_mindlin.py, on the code before and after the tangential
damping became sqrt(S_n m*) times a pair table - the same product, rounded differently) gave
torques -8.37 to -11.31 N m (mean -9.11, std 0.85), shell heat flows 13212 - 14016 W (mean
13565, std 206) and residences 2.77 - 3.00 s (mean 2.87, std 0.069): a granular flow is
chaotic, and a change in the last bit of the contacts' damping moves the 6 s mean torque by
up to 25 % (why its tail is that long was not looked into). The tolerances are therefore 3 times
the larger of the two spreads (torque +- 2.54 N m, shell heat flow +- 618 W, 4.6 %; residence
keeps +- 0.31 s); the means stay the seeds', which the perturbed runs' agree with (-8.98
against -9.11 N m, 13534 against 13565 W).

The residence pin moved on 2026-12-06: on that day's machine (same code: the tree of
2026-12-05 gives the same 2.629 s) seed 1 read 2.629 s and seeds 2-4 2.698, 2.938 and 2.858 s
(tests/regression/cooler_reference.py 2 3 4; torques -7.76, -8.95, -9.07 N m, shell heat
flows 13138 - 13625 W, inside the pins): every seed's trajectory had changed, as the last bit
of a library's arithmetic (a numpy or OpenBLAS kernel picked for the processor) changes a
chaotic flow's. The residence is pinned to the eight runs of the two machines, seeds 1-4 each:
mean 2.870 s, std 0.150 (+- 0.45 s at 3 std), a scatter of machines as well as of seeds.
"""
import numpy as np
import pytest

from cooler_reference import T0, UNTIL, run

TORQUE_MEAN, TORQUE_STD = -8.982, 0.848         # (std: the round-off runs', above)
RESIDENCE_MEAN, RESIDENCE_STD = 2.870, 0.150       # (seeds 1-4 on two machines, above)
SHELL_HEAT_MEAN, SHELL_HEAT_STD = 13534.0, 206.0  # (std: the round-off runs', above)


HEAT: dict = {}


@pytest.fixture(scope="module")
def cooler():
    return run(1, HEAT)


def test_shaft_torque(cooler):
    torque, _, _ = cooler
    assert abs(torque - TORQUE_MEAN) < 3 * TORQUE_STD, torque


def test_residence_time(cooler):
    _, residence, n = cooler
    assert n > 500
    assert abs(residence - RESIDENCE_MEAN) < 3 * RESIDENCE_STD, residence


def test_energy_balance_in_f32(cooler):
    # the heat the ash lost (fed - removed - inside, sum m c T) is the heat the water-cooled
    # shell took, to 1 % in the demo's own f32 (issue 10 item 6; both are sums of the same
    # per-step flows, so they agree far better: 1e-6 measured)
    loss, wall = HEAT["particle_heat_loss"], HEAT["wall_heat"]
    assert wall > 0.0 and HEAT["shell_heat_flow"] > 0.0
    assert abs(loss - wall) < 0.01 * wall, (loss, wall)


def test_shell_heat_flow(cooler):
    # the coarse-grained wall law at work: 26x the 510 W of 30 mm spheres (BENCHMARKS.md)
    # (a law that lost it would read 510 W; one that doubled it, 27,000 W: both far outside)
    assert abs(HEAT["shell_heat_flow"] - SHELL_HEAT_MEAN) < 3 * SHELL_HEAT_STD, HEAT["shell_heat_flow"]
