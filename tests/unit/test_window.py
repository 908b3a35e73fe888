"""The live window (`--window`, taichi_dem/app/window.py) really opened: under Xvfb with Mesa's
software Vulkan (lavapipe), on tests/unit/window_scene.toml (160 beads beside a paddle turning
at 20 rpm). tests/unit/window_check.py runs the window in its own process, screenshots frame 2
and presses keys with xdotool, which sends real X key events through GLFW into GGUI's event
queue (the window's own key handling, not a call into it): Up at frame 3, space at 5 and 7,
w (wireframe bodies) at 9, Esc at 11.

Skipped where xvfb-run, xdotool or a Vulkan driver is missing (Debian: apt-get install xvfb
xdotool mesa-vulkan-drivers). About 15 s, most of it compiling."""
from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT

HERE = Path(__file__).parent
MISSING = [tool for tool in ("xvfb-run", "Xvfb", "xdotool") if shutil.which(tool) is None]
if not glob.glob("/usr/share/vulkan/icd.d/*.json") + glob.glob("/etc/vulkan/icd.d/*.json"):
    MISSING.append("a Vulkan driver (mesa-vulkan-drivers)")
pytestmark = pytest.mark.skipif(bool(MISSING), reason=f"no {', '.join(MISSING)} here")


@pytest.fixture(scope="module")
def shown(tmp_path_factory):
    out = tmp_path_factory.mktemp("window")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    r = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", sys.executable,
                        str(HERE / "window_check.py"), str(HERE / "window_scene.toml"), str(out)],
                       capture_output=True, text=True, cwd=ROOT, timeout=400, env=env)
    assert r.returncode == 0, (r.stdout[-2000:], r.stderr[-3000:])
    report = json.loads(r.stdout.strip().splitlines()[-1])
    from PIL import Image
    png = np.asarray(Image.open(out / "frame.png"))[..., :3] / 255.0
    return report, png, out


def _in_triangles(points, vertices, faces, radius=0.0):
    from matplotlib.path import Path as MPath
    inside = np.zeros(len(points), bool)
    for f in faces:
        inside |= MPath(vertices[f]).contains_points(points, radius=radius)
    return inside


def test_particles_and_body_are_drawn_where_they_are(shown):
    """Pixel positions from GGUI's own view and projection matrices: every particle not behind
    the paddle is a coloured sphere on the screenshot, the paddle's triangles are grey, the
    coloured pixels are all near a particle, the rest is the black background."""
    report, png, out = shown
    assert report["particles"] == 160
    h, w = png.shape[:2]
    assert (w, h) == (640, 480) and report["image_shape"][:2] == [640, 480]
    chroma = png.max(axis=2) - png.min(axis=2)
    bright = png.max(axis=2)
    gui = np.zeros((h, w), bool)
    gui[:85, :200] = True                       # the text panel, top left
    flip = lambda p: np.c_[p[:, 0], h - p[:, 1]]           # NDC y up -> image rows down
    centres = flip(np.load(out / "particles_px.npy"))
    body = flip(np.load(out / "body_px.npy"))
    faces = np.load(out / "body_faces.npy")
    assert np.all((centres[:, 0] > 1) & (centres[:, 0] < w - 2) & (centres[:, 1] > 1)
                  & (centres[:, 1] < h - 2))
    behind = _in_triangles(centres, body, faces)
    assert behind.sum() < 0.5 * len(centres)
    c, r = np.round(centres[:, 0]).astype(int), np.round(centres[:, 1]).astype(int)
    near = np.max([chroma[r + dr, c + dc] for dr in (-1, 0, 1) for dc in (-1, 0, 1)], axis=0)
    assert np.all(near[~behind] > 0.1), np.sort(near[~behind])[:5]
    # the paddle: grey (0.6, 0.6, 0.65 lit), inside its projected triangles
    pixels = np.c_[np.tile(np.arange(w), h), np.repeat(np.arange(h), w)]
    on_body = _in_triangles(pixels, body, faces).reshape(h, w)
    grey = (chroma < 0.08) & (bright > 0.15)
    assert on_body.sum() > 2000
    assert grey[on_body].mean() > 0.95
    gy, gx = np.nonzero(grey & ~gui)
    assert _in_triangles(np.c_[gx, gy], body, faces, radius=2.0).mean() > 0.97
    # coloured pixels are spheres around the particle centres (radius ~12 px here)
    yy, xx = np.nonzero((chroma > 0.1) & ~gui)
    assert len(xx) > 5000
    d = np.sqrt(((np.c_[xx, yy][:, None, :] - centres[None, :, :]) ** 2).sum(-1)).min(axis=1)
    assert d.max() < 20.0
    # and away from everything, the background
    empty = ~gui & ~on_body
    empty[max(0, int(centres[:, 1].min()) - 20):int(centres[:, 1].max()) + 20,
          max(0, int(centres[:, 0].min()) - 20):int(centres[:, 0].max()) + 20] = False
    assert empty.sum() > 0.3 * w * h and np.mean(bright[empty] < 0.02) > 0.99


def test_up_key_raises_the_paddle_speed_and_space_pauses(shown):
    report = shown[0]
    speeds = {f: (t, w) for f, t, w in report["speeds"]}
    rpm = lambda w: w * 60 / (2 * np.pi)
    pressed = {f: k for f, k, _ in report["pressed"]}
    assert pressed == {3: "Up", 5: "space", 7: "space", 9: "w", 11: "Escape"}
    assert report["xdotool_window"]
    # the key pressed after frame 3 is handled before frame 4 is stepped: 20 -> 22 rpm (10 %)
    assert all(rpm(speeds[f][1]) == pytest.approx(20.0) for f in range(4))
    assert all(rpm(speeds[f][1]) == pytest.approx(22.0) for f in range(4, 12))
    # space after frame 5: frames 6 and 7 are not stepped; space again: stepping resumes
    assert speeds[6][0] == speeds[5][0] == speeds[7][0]
    assert speeds[8][0] > speeds[7][0] and speeds[5][0] > speeds[4][0]
    # Esc after frame 11 closes the run, long before end_time (1 s)
    assert report["frames"] == 12 and report["end_time"] < 0.3


def test_w_key_draws_the_bodies_as_wireframes(shown):
    """After w the paddle is edges only: its solid grey faces are gone (the screenshot of
    frame 10 against frame 2), the particles are still drawn."""
    from PIL import Image
    _, solid, out = shown
    wire = np.asarray(Image.open(out / "wireframe.png"))[..., :3] / 255.0
    grey = lambda im: ((im.max(axis=2) - im.min(axis=2)) < 0.08) & (im.max(axis=2) > 0.15)
    coloured = lambda im: (im.max(axis=2) - im.min(axis=2)) > 0.1
    assert grey(solid).sum() > 5000
    assert grey(wire).sum() < 0.3 * grey(solid).sum()
    assert coloured(wire).sum() > 0.8 * coloured(solid).sum()
