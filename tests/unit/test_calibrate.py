"""`taichi-dem calibrate` (taichi_dem/app/calibrate/): the spec's validation (exit 2 naming
the spec file and the dotted key), the response-surface fit and the optimiser on synthetic
responses with a known optimum, the record writer, and one tiny end-to-end calibration (a heap
of 200 spheres from a lifted tube, 2 design points + 1 verification run on a LocalCluster of 2
workers)."""
import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from taichi_dem.app import calibrate as cal
from taichi_dem.scene.loader import parse_scene

HEAP = """
[simulation]
end_time = 0.6
dt = 1.0e-4
gravity = [0.0, 0.0, -9.81]
precision = "f32"
seed = 1

[domain]
min = [-0.2, -0.2, -0.05]
max = [0.2, 0.2, 0.4]

[materials.grain]
density = 1000.0
youngs_modulus = 1.0e6
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3

[[interactions]]
pair = ["grain", "grain"]
restitution = 0.5
friction = 0.6
rolling_friction = 0.3

[[interactions]]
pair = ["grain", "steel"]
restitution = 0.5
friction = 0.8
rolling_friction = 0.3

[[walls]]
name = "floor"
plane = { point = [0, 0, 0], normal = [0, 0, 1] }
material = "steel"

[[bodies]]
name = "tube"
material = "steel"
mesh = { builder = "drum", radius = 0.04, length = 0.3, end_walls = false, axis_direction = [0, 0, 1], origin = [0, 0, -0.02] }
motion = { translate = { velocity = [0.0, 0.0, 0.4] } }

[[particles]]
material = "grain"
radius = 0.006
count = 200
region = { cylinder = { axis_point = [0, 0, 0.007], axis_direction = [0, 0, 1], radius = 0.038, length = 0.25 } }

[output]
interval = 0.05
"""

SPEC = """
[calibration]
material = "grain"
title = "tiny heap"

[design]
kind = "full_factorial"
verify_seeds = 1

[[parameters]]
key = "interactions.0.rolling_friction"
range = [0.05, 0.6]
values = [0.05, 0.6]

[[tests]]
kind = "angle_of_repose"
scene = "heap.toml"
measured = [24.0, 26.0, 25.0]

[[tests]]
name = "heap_density"
kind = "bulk_density"
scene = "heap.toml"
region = { radius = 0.03, z_min = 0.0, z_max = 0.02 }
mean = 600.0
sd = 50.0
"""


def _write(tmp_path, spec=SPEC, heap=HEAP):
    (tmp_path / "heap.toml").write_text(heap)
    path = tmp_path / "spec.toml"
    path.write_text(spec)
    return path


# ------------------------------------------------------------------------------ validation
BAD = [
    ("[calibraton]\nmaterial = 'grain'\n" + SPEC.split("[design]")[1].join(["[design]", ""]),
     "calibraton", "unknown key"),
    (SPEC.replace("range = [0.05, 0.6]", "range = [0.6, 0.05]"), "parameters.0.range", "low end"),
    (SPEC.replace("measured = [24.0, 26.0, 25.0]", "measured = [25.0]"), "tests.0.measured",
     "at least two"),
    (SPEC.replace('kind = "angle_of_repose"', 'kind = "slump"'), "tests.0.kind", "slump"),
    (SPEC.replace('scene = "heap.toml"\nmeasured', 'scene = "nope.toml"\nmeasured'), "tests.0.scene",
     "no such scene"),
    (SPEC.replace('kind = "full_factorial"', 'kind = "random"'), "design.kind", "random"),
    (SPEC.replace("verify_seeds = 1", "verify_seeds = 0"), "design.verify_seeds", ">= 1"),
    (SPEC.replace("mean = 600.0\nsd = 50.0", "mean = 600.0\nsd = -1.0"), "tests.1.sd", "> 0"),
    (SPEC.replace("region = { radius = 0.03, z_min = 0.0, z_max = 0.02 }\n", ""), "tests.1.region",
     "region"),
    (SPEC.replace("interactions.0.rolling_friction", "interactions.0.rolling_frction"),
     "parameters.0.key", "rolling_frction"),
    (SPEC.replace("interactions.0.rolling_friction", "interactions.5.rolling_friction"),
     "parameters.0.key", "index 5"),
    (SPEC.replace("range = [0.05, 0.6]\nvalues = [0.05, 0.6]", "range = [-0.5, 0.6]\nvalues = [-0.5, 0.6]"),
     "parameters.0.range", "rolling_friction"),
    (SPEC + '\n[[factors]]\nkeys = ["interactions.0.model"]\nlevels = ["epsd", "sticky"]\n',
     "factors.0.levels", "sticky"),
    (SPEC.replace("title = ", "title = = "), "", "not valid TOML"),
]


@pytest.mark.parametrize("text,key,reason", BAD, ids=[b[1] or b[2] for b in BAD])
def test_bad_spec_exits_2_naming_the_key(tmp_path, capsys, text, key, reason):
    """Each broken spec exits 2 with one paragraph naming the spec file, the dotted key and the
    reason, without a traceback and before any run starts (no runs/ directory is made)."""
    path = _write(tmp_path, text)
    rc = cal.main([str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "Traceback" not in err
    assert str(path) in err
    assert f": {key}: " in err if key else True, err
    assert reason in err, err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out" / "runs").exists()


def test_good_spec_reads(tmp_path):
    """The valid spec: measured repeats give the target mean and the sample standard deviation."""
    spec = cal.load_spec(str(_write(tmp_path)))
    assert spec.tests[0].target == pytest.approx(25.0)
    assert spec.tests[0].target_sd == pytest.approx(1.0)
    assert spec.tests[1].name == "heap_density" and spec.tests[1].target_sd == 50.0
    assert [p[spec.parameters[0].key] for p in cal.design_points(spec)] == [0.05, 0.6]


# ------------------------------------------------------------------------------ fit and optimum
def test_quadratic_fit_recovers_a_known_surface():
    """A quadratic in 2 scaled parameters is recovered to rounding (R^2 = 1); with Gaussian noise
    of sd 0.5 on 200 points the residual sd comes out within 20 % of 0.5 (its relative scatter
    is 1/sqrt(2 x 194) = 5 %, so 20 % is four standard deviations) and R^2 stays high."""
    rng = np.random.default_rng(4)
    x = rng.uniform(-1, 1, (200, 2))
    truth = np.array([30.0, 4.0, -2.0, -3.0, 1.5, 0.8])      # 1, x, y, x^2, y^2, xy
    y = cal.design_matrix(x, "quadratic") @ truth
    s = cal.fit_surface(x, y)
    assert s.model == "quadratic"
    np.testing.assert_allclose(s.coef, truth, atol=1e-9)
    assert s.r2 == pytest.approx(1.0, abs=1e-12)
    noisy = cal.fit_surface(x, y + rng.normal(0, 0.5, len(y)))
    assert noisy.residual_sd == pytest.approx(0.5, rel=0.2)
    assert noisy.r2 > 0.9
    few = cal.fit_surface(x[:4], y[:4])                # 4 points: too few for 6 coefficients
    assert few.model == "linear"


SYN_SPEC = """
[calibration]
material = "grain"
title = "synthetic"

[design]
kind = "full_factorial"
levels = 4

[[parameters]]
key = "interactions.0.rolling_friction"
range = [0.0, 1.0]

[[parameters]]
key = "interactions.1.rolling_friction"
range = [0.0, 1.0]

[[factors]]
name = "rolling model"
keys = ["interactions.0.model", "interactions.1.model"]
levels = ["epsd", "constant_torque"]

[[tests]]
name = "angle"
kind = "angle_of_repose"
scene = "heap.toml"
mean = 38.36
sd = 0.8

[[tests]]
name = "density"
kind = "bulk_density"
scene = "heap.toml"
region = { radius = 0.03, z_min = 0.0, z_max = 0.02 }
mean = 495.0
sd = 10.0
"""


def _synthetic(a, b, level):
    """Two synthetic bench responses: under epsd the angle cannot pass 30 deg; under
    constant_torque both targets are met at exactly (a, b) = (0.4, 0.7), the only solution
    in the unit square (29 + 25 a - 4 a^2 = 38.36 has its other root at a = 5.85)."""
    if level == "epsd":
        return 20.0 + 10.0 * a, 450.0 + 20.0 * b
    return 30.0 + 5.0 * a + 10.0 * b - 4.0 * a * a, 500.0 - 100.0 * a + 50.0 * b


def _fit_synthetic(tmp_path):
    spec = cal.load_spec(str(_write(tmp_path, SYN_SPEC)))
    points = cal.design_points(spec)
    resp = {}
    for ci, pt in enumerate(points):
        vals = _synthetic(pt["interactions.0.rolling_friction"], pt["interactions.1.rolling_friction"],
                          pt["interactions.0.model"])
        for ti, v in enumerate(vals):
            resp[(ti, ci)] = [v]
    return spec, points, resp, cal.fit_design(spec, points, resp)


def test_optimum_found_on_synthetic_responses(tmp_path):
    """The fit and the optimiser find the known optimum (0.4, 0.7) at the constant-torque
    level to 1e-3 (the optimiser's tolerance; the surfaces are exact quadratics), choose that
    level, and report the epsd level's angle as out of reach (20 - 30 deg against 38.36)."""
    spec, points, resp, (per_level, best, optimum) = _fit_synthetic(tmp_path)
    assert len(points) == 32
    assert best["level"] == ("constant_torque",)
    assert optimum["interactions.0.model"] == optimum["interactions.1.model"] == "constant_torque"
    assert optimum["interactions.0.rolling_friction"] == pytest.approx(0.4, abs=1e-3)
    assert optimum["interactions.1.rolling_friction"] == pytest.approx(0.7, abs=1e-3)
    assert best["chi2"] < 1e-4
    epsd = next(r for r in per_level if r["level"] == ("epsd",))
    lo, hi = epsd["reach"][0]
    assert (lo, hi) == (pytest.approx(20.0, abs=1e-6), pytest.approx(30.0, abs=1e-6))
    assert epsd["x"][0] == pytest.approx(1.0)           # pushed to the top of its range


def test_record_writer(tmp_path):
    """The outputs of a (synthetic) calibration: calibrated_material.toml reads back as TOML; its
    record holds the tests with targets, scatter and achieved values, the parameters with their
    ranges and values, the sphere radius of the base scene; the blocks above the record, pasted
    into the base scene, load and carry the calibrated values; calibration.md says which target
    is out of reach; the PNG is written."""
    spec, points, resp, (per_level, best, optimum) = _fit_synthetic(tmp_path)
    vresp = {(0, 0): [38.1, 37.6, 38.9], (1, 0): [497.0, 490.0, 501.0]}
    out = tmp_path / "out"
    out.mkdir()
    result = cal.assemble(spec, points, [], [], resp, per_level, best, optimum, [], [], vresp,
                          "taichi-dem calibrate spec.toml --out out", out)
    cal.write_outputs(result, spec, out)
    text = (out / "calibrated_material.toml").read_text()
    doc = tomllib.loads(text)
    rec = doc["materials"]["grain"]["calibration"]
    assert rec["command"] == "taichi-dem calibrate spec.toml --out out"
    assert rec["sphere_radius"] == [0.006]
    t0 = rec["tests"][0]
    assert t0["achieved"] == [38.1, 37.6, 38.9]
    assert t0["achieved_mean"] == pytest.approx(np.mean([38.1, 37.6, 38.9]))
    assert t0["achieved_sd"] == pytest.approx(np.std([38.1, 37.6, 38.9], ddof=1))
    assert t0["target"] == 38.36 and t0["target_sd"] == 0.8 and t0["within_scatter"] is True
    assert rec["tests"][1]["within_scatter"] is True
    assert rec["parameters"][0]["range"] == [0.0, 1.0]
    assert rec["parameters"][0]["value"] == pytest.approx(0.4, abs=1e-3)
    assert rec["factors"][0]["value"] == "constant_torque"
    assert rec["design"]["kind"] == "full_factorial" and rec["design"]["levels"] == [4, 4]
    # paste the blocks (everything above the record) into the base scene
    pasted = tomllib.loads(text.split("# ---- calibration record")[0])
    base = tomllib.loads(HEAP)
    base["materials"]["grain"] = pasted["materials"]["grain"]
    base["interactions"] = pasted["interactions"]
    from taichi_dem.app import overrides as ov
    scene = parse_scene(ov.to_text(base), source=str(tmp_path / "heap.toml"))
    assert len(scene.interactions) == 2
    assert pasted["interactions"][0]["rolling_friction"] == pytest.approx(0.4, abs=1e-3)
    assert pasted["interactions"][1]["model"] == "constant_torque"
    md = (out / "calibration.md").read_text()
    assert "epsd: angle reaches only 20 - 30 deg" in md
    assert (out / "calibration_response.png").stat().st_size > 10_000


# ------------------------------------------------------------------------------ end to end
@pytest.mark.two_cores
def test_tiny_calibration_end_to_end(tmp_path, capsys):
    """A real calibration: 2 design points (rolling friction 0.05 and 0.6) and 1 verification
    run, on a LocalCluster of 2 workers. Checked: the heap stands steeper at the higher rolling
    friction (by more than 3 deg: rolling resistance is what holds a sphere heap up); the
    record's achieved values are the responses read afresh from the verification run's results
    file; the command started again reuses every run."""
    path = _write(tmp_path)
    out = tmp_path / "out"
    rc = cal.main([str(path), "--out", str(out), "--workers", "2", "--quiet"])
    assert rc == 0, capsys.readouterr().err
    result = json.loads((out / "calibration.json").read_text())
    rows = result["design_rows"]
    assert [r["overrides"]["interactions.0.rolling_friction"] for r in rows] == [0.05, 0.6]
    assert rows[1]["angle_of_repose"][0] > rows[0]["angle_of_repose"][0] + 3.0
    assert all(math.isfinite(r["heap_density"][0]) for r in rows)
    ver = [v for v in result["verification"] if v["test"] == "angle_of_repose"][0]
    spec = cal.load_spec(str(path))
    again = cal.response(spec.tests[0], str(out / "runs" / ver["id"] / "results.h5"), "grain")
    rec = tomllib.loads((out / "calibrated_material.toml").read_text())["materials"]["grain"]["calibration"]
    assert rec["tests"][0]["achieved"] == [pytest.approx(again, abs=1e-9)]
    assert (out / "calibration.md").exists() and (out / "calibration_response.png").exists()
    capsys.readouterr()
    rc = cal.main([str(path), "--out", str(out), "--workers", "2"])
    err = capsys.readouterr().err
    assert rc == 0
    assert "already finished" in err and "running" not in err


# ------------------------------------------------------------------------------ the responses
def _results(path, frames, scene=HEAP, series=None):
    """A minimal results file: the scene text, /series and /frames/<k> (id, position, radius)."""
    import h5py
    with h5py.File(path, "w") as f:
        f.attrs["scene"] = scene
        s = f.create_group("series")
        for name, values in (series or {"time": np.zeros(1)}).items():
            s.create_dataset(name, data=np.asarray(values))
        for k, (pos, rad) in enumerate(frames):
            g = f.create_group(f"frames/{k}")
            g.create_dataset("id", data=np.arange(len(rad)))
            g.create_dataset("position", data=np.asarray(pos, float))
            g.create_dataset("radius", data=np.asarray(rad, float))
    return str(path)


def _test(kind, **options):
    return cal.BenchTest(kind, kind, "heap.toml", None, (), 1.0, 0.1, options)


def test_responses_from_synthetic_results(tmp_path):
    """Each bench test reads its quantity from a results file built with a known answer:
    a cone of 30 deg (to 0.5 deg: the rings' highest tops sample the cone on a 4 mm grid), a
    base of fixed spheres that never moved left out of it; a simple cubic lattice of spheres
    (solid fraction pi/6, to 1e-9 inside a region whose edges fall between centres); a lost
    count growing at 100 1/s (the discharge rate times the particle mass, to rounding); a drum
    bed whose surface tilts 25 deg (centres scattered densely below it; to 1 deg: the surface is
    the highest sphere top in one-diameter bins, a few tenths of a degree off a plane)."""
    r = 0.005
    # a cone: spheres on a 1 mm grid below z = (0.2 - rho) tan 30 deg, plus a fixed base layer
    g = np.arange(-0.2, 0.2001, 0.004)
    xx, yy = np.meshgrid(g, g)
    rho = np.hypot(xx, yy).ravel()
    top = np.clip((0.2 - rho) * math.tan(math.radians(30.0)), 0.0, None)
    cone = np.column_stack([xx.ravel(), yy.ravel(), np.maximum(top - r, r)])
    base = np.column_stack([xx.ravel(), yy.ravel(), np.full(len(rho), -r)])
    moved = cone.copy()
    start = cone + [0.0, 0.0, 0.1]                     # the heap's spheres fell; the base did not
    rad = np.full(2 * len(rho), r)
    h5 = _results(tmp_path / "cone.h5", [(np.vstack([start, base]), rad), (np.vstack([moved, base]), rad)])
    assert cal.response(_test("angle_of_repose"), h5, "grain") == pytest.approx(30.0, abs=0.5)
    # a simple cubic lattice of spacing 2 r: bulk density 1000 pi / 6
    g = np.arange(-0.05 + r, 0.05, 2 * r)
    lat = np.array(np.meshgrid(g, g, g + 0.05)).reshape(3, -1).T
    h5 = _results(tmp_path / "lattice.h5", [(lat, np.full(len(lat), r))] * 2)
    region = {"radius": 0.03, "z_min": 0.02, "z_max": 0.08, "centre": (0.0, 0.0)}
    inside = ((np.hypot(lat[:, 0], lat[:, 1]) < 0.03) & (lat[:, 2] > 0.02) & (lat[:, 2] < 0.08)).sum()
    expect = inside * 4 / 3 * math.pi * r ** 3 * 1000.0 / (math.pi * 0.03 ** 2 * 0.06)
    assert cal.response(_test("bulk_density", region=region), h5, "grain") == pytest.approx(expect, rel=1e-9)
    # a hopper: 100 particles, lost at 100 per second
    t = np.linspace(0, 1, 51)
    h5 = _results(tmp_path / "hopper.h5", [(lat[:100], np.full(100, r))],
                  series={"time": t, "particles/count": 100 - 100 * t, "particles/lost": 100 * t})
    mass = 4 / 3 * math.pi * r ** 3 * 1000.0
    assert cal.response(_test("discharge_rate"), h5, "grain") == pytest.approx(100 * mass, rel=1e-9)
    # a drum about the x axis: the bed below a plane tilted 25 deg across it
    y, z = np.random.default_rng(1).uniform(-0.1, 0.1, (2, 20000))      # dense: tops near the plane
    keep = (np.hypot(y, z) < 0.1 - r) & (z + r <= y * math.tan(math.radians(25.0)) + 1e-12)
    bed = np.column_stack([np.zeros(keep.sum()), y[keep], z[keep]])
    h5 = _results(tmp_path / "drum.h5", [(bed, np.full(len(bed), r))] * 2)
    angle = cal.response(_test("dynamic_angle", axis_point=(0, 0, 0), axis_direction=(1, 0, 0)), h5, "grain")
    assert angle == pytest.approx(25.0, abs=1.0)


@pytest.mark.parametrize("order", [["epsd", "constant_torque"], ["constant_torque", "epsd"]])
def test_equally_good_levels_go_to_the_first_listed(tmp_path, order):
    """Two levels with the same responses meet the targets equally: the level listed first in
    the spec is taken (the spec orders the levels by preference), whichever it is."""
    text = SYN_SPEC.replace('levels = ["epsd", "constant_torque"]', f"levels = {json.dumps(order)}")
    spec = cal.load_spec(str(_write(tmp_path, text)))
    points = cal.design_points(spec)
    resp = {}
    for ci, pt in enumerate(points):
        vals = _synthetic(pt["interactions.0.rolling_friction"], pt["interactions.1.rolling_friction"],
                          "constant_torque")
        for ti, v in enumerate(vals):
            resp[(ti, ci)] = [v]
    per_level, best, optimum = cal.fit_design(spec, points, resp)
    assert best["level"] == (order[0],)
    assert optimum["interactions.0.model"] == order[0]


def test_design_seeds_differ_between_points_and_match_across_levels(tmp_path):
    """Every continuous design point gets its own placement seeds (a seed shared by all points
    would shift the whole fitted surface by that one placement's offset), the same at each level
    of the factors; the verification's seeds lie past every design seed."""
    text = SYN_SPEC.replace("levels = 4", "levels = 3\nseeds = 2")
    spec = cal.load_spec(str(_write(tmp_path, text)))
    points = cal.design_points(spec)
    planned = cal._plan(spec, points, spec.seeds, 1, "cpu")
    seeds = {}
    for ti, ci, run in planned:
        if ti == 0:
            seeds.setdefault(ci, []).append(run.seed)
    n = len(points) // 2                                    # 9 continuous points x 2 levels
    first = [tuple(seeds[ci]) for ci in range(n)]
    assert len(set(first)) == n and all(len(set(s)) == 2 for s in first)
    assert len({x for s in first for x in s}) == 2 * n       # no seed used by two points
    assert [tuple(seeds[ci + n]) for ci in range(n)] == first
    assert cal.verification_offset(spec, len(points)) + 1 > max(x for s in first for x in s)


# ------------------------------------------------------------------------------ the sequential method
def test_repeated_runs_weigh_by_their_number():
    """Runs repeated at a point enter the fit as their mean weighted by their number: the
    coefficients equal ordinary least squares over every run (to rounding, 1e-9), the residual
    sd is over the runs, and the run-to-run scatter at the repeated points (pure error) is the
    pooled sample sd of the repeats (exact arithmetic, so 1e-9)."""
    rng = np.random.default_rng(7)
    x = rng.uniform(-1, 1, (6, 2))
    reps = np.array([1, 1, 1, 8, 1, 4])
    xr = np.repeat(x, reps, axis=0)
    yr = 30.0 + 3.0 * xr[:, 0] - 2.0 * xr[:, 1] + rng.normal(0, 1.5, len(xr))
    s = cal.fit_surface(xr, yr, "linear")
    a = cal.design_matrix(xr, "linear")
    coef, *_ = np.linalg.lstsq(a, yr, rcond=None)
    np.testing.assert_allclose(s.coef, coef, atol=1e-9)
    res = yr - a @ coef
    assert s.residual_sd == pytest.approx(math.sqrt(res @ res / (len(yr) - 3)), rel=1e-9)
    assert (s.n, s.points) == (16, 6)
    starts = np.cumsum(reps) - reps
    groups = [yr[i:i + k] for i, k in zip(starts, reps) if k > 1]
    pooled = sum(float(np.sum((g - g.mean()) ** 2)) for g in groups) / sum(len(g) - 1 for g in groups)
    assert s.pure_sd == pytest.approx(math.sqrt(pooled), rel=1e-9)
    # the standard error of the surface is smallest where the 8 repeats are
    se = s.se(x)
    assert int(np.argmin(se)) == 3


def test_model_no_richer_than_the_points_support():
    """Nine Latin-hypercube points of a plane with heap-like noise (sd 2 on a 6-deg slope, as
    the fly-ash design): the 6-coefficient quadratic chases the noise, and leave-one-point-out
    error picks the linear surface in each of 20 noise draws out of at least 16 (a quadratic
    wins in only a few draws by chance). With 40 points of a strong quadratic and noise sd 0.3
    the quadratic is chosen. The choice is by the smallest LOO error, the candidates' errors
    are kept."""
    from scipy.stats import qmc
    x9 = qmc.LatinHypercube(d=2, seed=1).random(9) * 2 - 1
    linear_wins = 0
    for k in range(20):
        rng = np.random.default_rng(100 + k)
        y = 32.0 + 4.0 * x9[:, 0] + 2.0 * x9[:, 1] + rng.normal(0, 2.0, 9)
        s = cal.choose_surface(x9, y)
        assert s.loo_rmse == min(s.tried.values())
        linear_wins += s.model == "linear"
    assert linear_wins >= 16
    rng = np.random.default_rng(3)
    x40 = rng.uniform(-1, 1, (40, 2))
    y = 30 + 2 * x40[:, 0] - 6 * x40[:, 0] ** 2 + 3 * x40[:, 1] ** 2 + rng.normal(0, 0.3, 40)
    assert cal.choose_surface(x40, y).model == "quadratic"


SEQ_SPEC = """
[calibration]
material = "grain"
title = "synthetic sequential"

[design]
kind = "latin_hypercube"
points = 9
seed = 1
verify_seeds = 8
rounds = ROUNDS

[[parameters]]
key = "interactions.0.rolling_friction"
range = [0.05, 1.5]

[[parameters]]
key = "interactions.1.rolling_friction"
range = [0.05, 1.5]

[[factors]]
name = "rolling model"
keys = ["interactions.0.model", "interactions.1.model"]
levels = ["epsd", "constant_torque"]

[[tests]]
kind = "angle_of_repose"
scene = "heap.toml"
mean = 38.04
sd = 0.81
"""


def _true_angle(o, steel_gain=5.0):
    """A synthetic heap that saturates in the ash-ash rolling friction as a real one does: under
    epsd it tops out at 36 deg (the target 38.04 is out of reach), under constant torque it
    reaches 38.04 only with the ash-steel rolling friction in the upper part of its range (with
    ``steel_gain`` 4.5: only within ~0.1 of the corner (1.5, 1.5), at 38.35 deg)."""
    a, b = o["interactions.0.rolling_friction"], o["interactions.1.rolling_friction"]
    if o["interactions.0.model"] == "epsd":
        return 20.0 + 14.0 * (1 - math.exp(-3 * a)) + 2.0 * b / 1.5
    return 20.0 + 14.0 * (1 - math.exp(-3 * a)) + steel_gain * b / 1.5


def _fake_runs(monkeypatch, noise_sd, steel_gain=5.0):
    """No simulation: every planned run 'finishes' at once and its response is the synthetic
    heap plus Gaussian noise drawn from the run's seed and overrides (a fresh placement gives a
    fresh draw, the same run read again gives the same value)."""
    import zlib

    def sweep(specs, out, state, progress, timeout):
        return [{"id": s.id, "status": "done", "wall_s": 1.0, "cpu_s": 1.0} for s in specs]

    def responses(spec, planned, records, out):
        res = {}
        for ti, ci, s in planned:
            noise = np.random.default_rng(zlib.crc32(s.id.encode())).normal(0, noise_sd) if noise_sd else 0.0
            res.setdefault((ti, ci), []).append(_true_angle(s.overrides, steel_gain) + noise)
        return res
    # (the rounds' module runs them: taichi_dem/app/calibrate/rounds.py)
    monkeypatch.setattr(cal.rounds, "_sweep", sweep)
    monkeypatch.setattr(cal.rounds, "_responses", responses)


def test_sequential_design_reaches_a_known_optimum_through_noise(tmp_path, monkeypatch):
    """On the synthetic noisy heap (sd 2 deg per run, as the fly-ash heaps; target 38.04 +- 0.81)
    the rounds go on until a verification passes: every failed round's verification joins the
    design (weighted by its 8 runs) and an optimum on a range's edge brings new points near it;
    the written optimum is at constant torque (the only level that reaches the target) and its
    noise-free heap lies within 1.5 target sd of the target (the 8-run mean has a standard error
    of 0.7 deg, so a passing verification can sit up to ~0.8 + 2 x 0.7 deg off the truth). With
    one round only, the same noise leaves the first (epsd) optimum not calibrated."""
    _fake_runs(monkeypatch, 2.0)
    path = _write(tmp_path, SEQ_SPEC.replace("ROUNDS", "6"))
    spec = cal.load_spec(str(path))
    result = cal.calibrate(spec, str(tmp_path / "out"), progress=False)
    rounds = result["rounds"]
    assert result["within_scatter"] and rounds[-1]["passed"]
    assert all(not r["passed"] for r in rounds[:-1])
    opt = result["optimum"]
    assert opt["interactions.0.model"] == "constant_torque"
    assert abs(_true_angle(opt) - 38.04) <= 1.5 * 0.81
    t = result["tests"][0]
    assert len(t["achieved"]) == 8
    assert t["achieved_sem"] == pytest.approx(t["achieved_sd"] / math.sqrt(8))
    sources = [r["source"] for r in result["design_rows"]]
    assert sources.count("verification 1") == (1 if len(rounds) > 1 else 0)
    assert sum(s.startswith("verification") for s in sources) == len(rounds) - 1
    for k, rnd in enumerate(rounds[:-1]):
        row = next(r for r in result["design_rows"] if r["source"] == f"verification {k + 1}")
        assert row["overrides"] == rnd["optimum"] and len(row["angle_of_repose"]) == 8
        edge_rows = [r for r in result["design_rows"] if r["source"] == f"edge {k + 1}"]
        assert len(edge_rows) == (3 if rnd["on_edge"] else 0)
    md = (tmp_path / "out" / "calibration.md").read_text()
    assert "## Rounds" in md and "|achieved mean - target| <= target sd" in md
    # one round: the first optimum fails
    out1 = tmp_path / "one"
    spec1 = cal.load_spec(str(_write(tmp_path, SEQ_SPEC.replace("ROUNDS", "1"))))
    one = cal.calibrate(spec1, str(out1), progress=False)
    assert len(one["rounds"]) == 1
    assert one["rounds"][0]["optimum"] == rounds[0]["optimum"]
    assert one["within_scatter"] == rounds[0]["passed"]


def test_edge_optimum_pulls_points_there(tmp_path):
    """An optimum on the upper edge of the second range gets `augment` new points (default:
    parameters + 1 = 3) at its level, inside the ranges, within a box of 1/4 of each range that
    touches that edge; the seeds of a round's verification and edge points do not collide with
    the design's or another round's."""
    spec = cal.load_spec(str(_write(tmp_path, SEQ_SPEC.replace("ROUNDS", "3"))))
    opt = {"interactions.0.model": "constant_torque", "interactions.1.model": "constant_torque",
           "interactions.0.rolling_friction": 0.9, "interactions.1.rolling_friction": 1.5}
    assert cal.on_edge(spec, opt) == ["interactions.1.rolling_friction"]
    pts = cal.augment_points(spec, opt, 0)
    assert len(pts) == 3
    for p in pts:
        assert p["interactions.0.model"] == "constant_torque"
        assert 1.5 - 0.25 * 1.45 - 1e-9 <= p["interactions.1.rolling_friction"] <= 1.5
        assert abs(p["interactions.0.rolling_friction"] - 0.9) <= 0.125 * 1.45 + 1e-9
    assert max(p["interactions.1.rolling_friction"] for p in pts) > 1.5 - 0.1 * 1.45
    stride = cal.round_stride(spec)
    first = cal.verification_offset(spec, len(cal.design_points(spec)))
    assert first > 9 and stride >= spec.verify_seeds + 3
    assert cal.augment_points(spec, opt, 1) != pts


def test_bad_rounds_exit_2(tmp_path, capsys):
    """rounds = 0 and a negative augment are bad input: exit 2 naming design.rounds / design.augment."""
    for old, new, key in (("rounds = ROUNDS", "rounds = 0", "design.rounds"),
                          ("rounds = ROUNDS", "rounds = 2\naugment = -1", "design.augment")):
        path = _write(tmp_path, SEQ_SPEC.replace(old, new))
        rc = cal.main([str(path), "--out", str(tmp_path / "out"), "--quiet"])
        err = capsys.readouterr().err
        assert rc == 2 and f": {key}: " in err, err


def test_unreachable_target_on_the_edge_adds_points_there_and_says_not_calibrated(tmp_path, monkeypatch):
    """Constant torque only, with a heap that tops out at 36.85 deg in the corner (1.5, 1.5)
    (target 38.04 +- 0.81; noise sd 0.5): the first optimum lies on the ranges' edge, its
    verification fails, so round 2 gets the verification's 8 runs and 3 new points near that
    edge (inside the ranges, within 1/4 of each range of the corner); round 2 fails too and the
    result says not calibrated, written as such in calibration.md and the material file."""
    _fake_runs(monkeypatch, 0.5, steel_gain=3.0)
    text = SEQ_SPEC.replace("ROUNDS", "2").replace('levels = ["epsd", "constant_torque"]',
                                                   'levels = ["constant_torque"]')
    spec = cal.load_spec(str(_write(tmp_path, text)))
    result = cal.calibrate(spec, str(tmp_path / "out"), progress=False)
    r1, r2 = result["rounds"]
    assert r1["on_edge"] and not r1["passed"] and not r2["passed"]
    edge = [r for r in result["design_rows"] if r["source"] == "edge 1"]
    assert len(edge) == 3
    for row in edge:
        for key in ("interactions.0.rolling_friction", "interactions.1.rolling_friction"):
            v = row["overrides"][key]
            if key in r1["on_edge"]:
                assert 1.5 - 0.25 * 1.45 - 1e-9 <= v <= 1.5
    assert not result["within_scatter"]
    assert "**Not calibrated**" in (tmp_path / "out" / "calibration.md").read_text()
    assert "NOT CALIBRATED" in (tmp_path / "out" / "calibrated_material.toml").read_text()


def test_a_failed_level_loses_its_preference_in_a_tie(tmp_path):
    """Two levels with the same responses tie; the first listed is taken, unless its verified
    optimum already failed (then the other one, not yet disproved); when both have failed, the
    lower chi2 of the two. Checked on the synthetic surfaces of the tie test (exact quadratics)."""
    spec = cal.load_spec(str(_write(tmp_path, SYN_SPEC)))
    points = cal.design_points(spec)
    resp = {}
    for ci, pt in enumerate(points):
        vals = _synthetic(pt["interactions.0.rolling_friction"], pt["interactions.1.rolling_friction"],
                          "constant_torque")
        for ti, v in enumerate(vals):
            resp[(ti, ci)] = [v]
    assert cal.fit_design(spec, points, resp)[1]["level"] == ("epsd",)
    assert cal.fit_design(spec, points, resp, frozenset({("epsd",)}))[1]["level"] == ("constant_torque",)
    both = frozenset({("epsd",), ("constant_torque",)})
    per_level, best, _ = cal.fit_design(spec, points, resp, both)
    assert best["chi2"] == min(r["chi2"] for r in per_level)
