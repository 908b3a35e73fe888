"""A packed bed of 6.4 mm steel spheres heated from one wall for an hour, against Beaulieu's
measured temperatures 4.0, 6.0 and 7.3 cm into the bed (issue 32 item 2; the experiment is
tests/verification/heated_bed.py, the data and their source tests/reference/beaulieu_heated_bed/,
the figures and plot docs/verification/first_layer.md).

Measured with the default gas-gap model ("schlunder"), the rise after 4000 s against the
thermocouples': 0.86, 0.85 and 0.79 x at 4.0, 6.0 and 7.3 cm. The former default
("solid_resistance") gave 0.52, 0.35 and 0.22 x (the issue's figures, with the case held back).

Thermal time scaling S = 5000 (the experiment's default is 1000): the bed is at rest once
settled, so its mechanics set no limit, and the explicit conduction step stays far inside its
own (m c / (S sum G) ~ 1e-3 s for sum G ~ 0.1 W/K, against dt = 2.6e-5 s). The rises after
4000 s with S = 1000 / 2000 / 5000 (2026-12-07, one run each, 69 / 41 / 24 s wall): 0.856 /
0.859 / 0.860 x at 4.0 cm, 0.854 / 0.859 / 0.858 x at 6.0 cm, 0.790 / 0.795 / 0.789 x at 7.3 cm:
the same within 0.01.

Asserted: the rise within 25 % of the measured one at 3000 and 4000 s at 4.0 and 6.0 cm, and at
4000 s at 7.3 cm. The 25 %: the measurement's own band (the digitised upper and lower curves)
is +-10 % of the rise at 4.0 cm, +-32 % at 6.0 cm and +-57 % at 7.3 cm after 4000 s; its
thermocouples' positions are known to a few mm (half a sphere), which at these gradients
(3.5 K/cm at 4 cm) is ~15 % of the rise. Earlier than 3000 s the rises at 6 and 7.3 cm are
within the digitising's scatter (~0.3 K) of zero and are not asserted.
"""
import pytest

from heated_bed import comparison, heated_bed


@pytest.fixture(scope="module")
def bed():
    r = heated_bed("schlunder", time_scale=5000.0)
    print(f"\n  porosity {r['porosity']:.3f}, {r['count']} spheres, {r['wall_seconds']:.0f} s wall")
    for depth, t, dem, exp, lo, hi in comparison(r):
        print(f"  {depth * 100:.1f} cm, {t:.0f} s: DEM rise {dem:.2f} K, measured {exp:.2f} "
              f"({lo:.2f} - {hi:.2f}), {dem / exp:.2f} x")
    return r


@pytest.mark.slow
def test_bed_is_a_random_packing_at_rest(bed):
    assert bed["lost"] == 0
    assert 0.38 < bed["porosity"] < 0.45         # the measured bed's ~0.42


@pytest.mark.slow
def test_heat_penetrates_as_measured(bed):
    rows = {(depth, t): (dem, exp) for depth, t, dem, exp, _, _ in comparison(bed)}
    for key in [(0.040, 3000.0), (0.040, 4000.0), (0.060, 3000.0), (0.060, 4000.0),
                (0.073, 4000.0)]:
        dem, exp = rows[key]
        assert dem == pytest.approx(exp, rel=0.25), key
