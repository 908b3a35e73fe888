"""``taichi-dem check SCENE --preview PNG``: the scene drawn at t = 0 without running it."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _check(*args):
    return subprocess.run([sys.executable, "-m", "taichi_dem", "check", *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)


@pytest.mark.parametrize("scene", ["demos/pile.toml", "demos/paddle_cooler.toml"])
def test_preview_draws_the_scene(scene, tmp_path):
    import matplotlib.image
    png = tmp_path / "preview.png"
    r = _check(scene, "--preview", str(png))
    assert r.returncode == 0, r.stderr
    assert f"preview: {png}" in r.stdout and "scene OK" in r.stdout
    image = matplotlib.image.imread(png)[..., :3]
    assert image.shape[0] > 300 and image.shape[1] > 600
    # not blank: a good part of the picture differs from the white background
    assert np.mean(np.any(image < 0.9, axis=-1)) > 0.05


def test_preview_is_not_taken_without_the_option(tmp_path):
    r = _check("demos/pile.toml")
    assert r.returncode == 0 and "preview" not in r.stdout


def test_an_unwritable_preview_is_refused(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = _check("demos/pile.toml", "--preview", str(blocker / "x.png"))
    assert r.returncode == 2 and "--preview" in r.stderr and "Traceback" not in r.stderr
