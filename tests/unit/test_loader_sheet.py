"""[[factories]] pattern = "sheet": the keys that load, and a clear error (file, key, reason)
for each bad input."""
import math

import numpy as np
import pytest

from test_loader import base, error, load


def sheet(**kw):
    f = {"name": "inlet", "material": "ash", "radius": 0.01, "pattern": "sheet",
         "face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.4, 0.0], "depth": [0.0, 0.0, 0.3]},
         "velocity": [0.5, 0.0, 0.0], "mass_rate": "5 kg/s"}
    f.update(kw)
    return f


def with_sheet(**kw):
    d = base()
    d["factories"] = [sheet(**kw)]
    for k in [k for k, v in kw.items() if v is None]:
        del d["factories"][0][k]
    return d


def test_sheet_loads_with_its_lattice():
    s = load(with_sheet(jitter=0.02))
    (f,) = s.factories
    assert f.pattern == "sheet" and f.region is None and f.sheet.normal == (1.0, 0.0, 0.0)
    sh = f.sheet
    assert sh.radius == 0.01 and sh.jitter == 0.02 and sh.extents == pytest.approx((0.4, 0.3))
    # pitch = contact distance (with its 1e-3 clearance) + twice the largest jitter displacement
    assert sh.pitch == pytest.approx(0.02 * 1.001 + 2 * 0.02 * 0.02)
    for parity in (0, 1):
        st = sh.sites(parity)
        margin = sh.radius + sh.jitter_amplitude
        assert st.min() >= margin - 1e-15
        assert np.all(st.max(axis=0) <= np.array(sh.extents) - margin + 1e-15)
    # every pair of sites of one layer, and of two successive layers at the least spacing, is
    # clear by twice the jitter (so the jittered spheres cannot touch)
    a = np.c_[np.zeros(len(sh.sites(0))), sh.sites(0)]
    b = np.c_[np.full(len(sh.sites(1)), sh.min_layer_spacing), sh.sites(1)]
    pts = np.concatenate([a, b])
    d2 = np.sum((pts[:, None] - pts[None]) ** 2, axis=-1)
    np.fill_diagonal(d2, np.inf)
    assert math.sqrt(d2.min()) >= 2 * sh.radius + 2 * sh.jitter_amplitude - 1e-12


def test_box_face_and_reversed_normal():
    # an axis-aligned face (one zero extent); the velocity decides which side the stream goes
    s = load(with_sheet(face={"min": [0.5, 0.1, 0.05], "max": [0.5, 0.5, 0.35]},
                        velocity=[-0.5, 0.0, -0.1]))
    sh = s.factories[0].sheet
    assert sh.normal == (-1.0, 0.0, 0.0) and sh.extents == pytest.approx((0.4, 0.3))


def test_max_rate_is_what_the_lattice_carries():
    s = load(with_sheet())
    sh = s.factories[0].sheet
    n0, n1 = sh.layer_counts()
    m = 870.0 * 4 / 3 * math.pi * 0.01 ** 3
    assert sh.max_mass_rate(870.0, 0.5) == pytest.approx(0.5 * (n0 + n1) * m * 0.5 / sh.min_layer_spacing)


@pytest.mark.parametrize("kw, key, frag", [
    ({"pattern": "lattice"}, "factories[0].pattern", "unknown pattern"),
    ({"region": {"box": {"min": [0, 0, 0], "max": [1, 1, 1]}}}, "factories[0].region", "face"),
    ({"sizes": [[0.01, 1.0]], "radius": None}, "factories[0].sizes", "one radius"),
    ({"interval": 0.1}, "factories[0].interval", "layer spacing"),
    ({"radius": {"mean": 0.01, "std": 0.001, "min": 0.008, "max": 0.012}}, "factories[0].radius",
     "one radius"),
    ({"face": None}, "factories[0].face", "required"),
    ({"velocity": None}, "factories[0].velocity", "required"),
    ({"mass_rate": "100 kg/s"}, "factories[0].mass_rate", "solid fraction"),
    ({"velocity": [0.0, 0.5, 0.0]}, "factories[0].velocity", "must cross its face"),
    ({"jitter": 0.3}, "factories[0].jitter", "at most 0.25"),
    ({"jitter": -0.1}, "factories[0].jitter", ">= 0"),
    ({"face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.4, 0.0], "depth": [0.0, 0.1, 0.3]}},
     "factories[0].face.depth", "perpendicular"),
    ({"face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.0, 0.0], "depth": [0.0, 0.0, 0.3]}},
     "factories[0].face.width", "nonzero"),
    ({"face": {"min": [0.5, 0.1, 0.05], "max": [0.6, 0.5, 0.35]}}, "factories[0].face.max",
     "exactly one axis"),
    ({"face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.4, 0.0]}}, "factories[0].face",
     "point, width and depth"),
    ({"face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.4, 0.0], "depth": [0.0, 0.0, 0.02]}},
     "factories[0].face", "narrower than one jittered sphere"),
    ({"face": {"point": [0.05, 0.7, 0.05], "width": [0.0, 0.4, 0.0], "depth": [0.0, 0.0, 0.3]}},
     "factories[0].face", "inside the domain"),
    ({"face": {"point": [0.05, 0.1, 0.05], "width": [0.0, 0.4, 0.0], "depth": [0.0, 0.0, 0.3],
               "normal": [1, 0, 0]}}, "factories[0].face.normal", "unknown key"),
])
def test_sheet_errors(kw, key, frag):
    error(with_sheet(**kw), key, frag)


def test_random_factories_refuse_sheet_keys():
    d = base()
    d["factories"] = [{"name": "inlet", "material": "ash", "radius": 0.01,
                       "region": {"box": {"min": [0.1, 0.1, 0.7], "max": [0.9, 0.9, 0.9]}},
                       "mass_rate": "1 kg/s", "jitter": 0.1}]
    error(d, "factories[0].jitter", 'only for pattern = "sheet"')


def test_loader_error_names_the_file(tmp_path):
    from test_loader import dumps
    from taichi_dem.errors import SceneError
    from taichi_dem.scene.loader import load_scene
    p = tmp_path / "inlet.toml"
    p.write_text(dumps(with_sheet(mass_rate="100 kg/s")))
    with pytest.raises(SceneError) as e:
        load_scene(str(p))
    assert str(e.value).startswith(str(p)) and "factories[0].mass_rate" in str(e.value)
