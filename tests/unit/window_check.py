"""Driven by tests/unit/test_window.py under Xvfb (a display with Mesa's software Vulkan):
open the live window (taichi_dem.app.window.run_window) on SCENE, screenshot frame 2 with the
pixel positions of the particles and the body's triangles (GGUI's own camera matrices), press
keys with xdotool (real X key events, through GLFW and GGUI's event queue: Up at frame 3,
space at 5 and 7, w at 9, Esc at 11), screenshot frame 10 (wireframe bodies) and print what
happened as JSON (per frame: time, speed).

    xvfb-run -s "-screen 0 1280x1024x24" python tests/unit/window_check.py SCENE OUT_DIR
"""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import taichi_dem as td                                  # noqa: E402
from taichi_dem.app.window import run_window             # noqa: E402
from taichi_dem.bodies.kinematics import rotation_matrix  # noqa: E402

SIZE = (640, 480)
SHOT = 2
PRESS = {3: "Up", 5: "space", 7: "space", 9: "w", 11: "Escape"}
WIRE = 10                               # a screenshot after "w": bodies as wireframes
LAST = 30                               # a safety stop: Esc at frame 11 ends the run


def project(camera, points):
    """Pixel (column, row) of world points, with GGUI's own view and projection matrices."""
    view = np.asarray(camera.get_view_matrix(), float)
    proj = np.asarray(camera.get_projection_matrix(SIZE[0] / SIZE[1]), float)
    h = np.c_[points, np.ones(len(points))]
    clip = h @ view @ proj                  # row-vector convention (GGUI's matrices, row major)
    ndc = clip[:, :3] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * SIZE[0], (ndc[:, 1] + 1) / 2 * SIZE[1]], ndc[:, 2]


def main(scene, out_dir):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sim = td.Simulation.from_toml(scene, arch="cpu")
    report = {"speeds": []}
    name = sim.scene.bodies[0].name

    def on_frame(window, camera, frame, keys):
        w = sim.engine.kinematics.speed(0, sim.time)
        report["speeds"].append([frame, sim.time, w])
        if frame == SHOT:
            window.save_image(str(out / "frame.png"))
            img = window.get_image_buffer_as_numpy()
            np.save(out / "frame.npy", img)
            p = sim.particles()
            px, _ = project(camera, p["position"])
            np.save(out / "particles_px.npy", px)
            np.save(out / "particles_radius.npy", p["radius"])
            b = sim.scene.bodies[0]
            m = b.motion
            rot = rotation_matrix(np.asarray(m.axis_direction, float),
                                  sim.engine.kinematics.angle(0, sim.time))
            ap = np.asarray(m.axis_point, float)
            v = (b.vertices - ap) @ rot.T + ap
            bx, _ = project(camera, v)
            np.save(out / "body_px.npy", bx)
            np.save(out / "body_faces.npy", np.asarray(b.faces))
            np.save(out / "body_centroids_px.npy", project(camera, v[np.asarray(b.faces)].mean(axis=1))[0])
            report["image_shape"] = list(img.shape)
            report["particles"] = len(p["id"])
        if frame == WIRE:
            window.save_image(str(out / "wireframe.png"))
        if frame in PRESS:
            # the pointer over the window gives it the keyboard (no window manager under Xvfb)
            r = subprocess.run(["xdotool", "search", "--name", "taichi-dem"], capture_output=True,
                               text=True)
            wid = r.stdout.split()[0] if r.stdout.split() else ""
            report["xdotool_window"] = wid
            subprocess.run(["xdotool", "mousemove", str(SIZE[0] // 2), str(SIZE[1] // 2)])
            if wid:
                subprocess.run(["xdotool", "windowfocus", "--sync", wid], capture_output=True)
            subprocess.run(["xdotool", "key", PRESS[frame]], check=True)
            report.setdefault("pressed", []).append([frame, PRESS[frame], sim.time])
        return frame < LAST

    run_window(sim, sim.scene.simulation.end_time, size=SIZE, vsync=False, on_frame=on_frame)
    report["frames"] = len(report["speeds"])
    report["end_time"] = sim.time
    report["rpm_before"] = report["speeds"][0][2] * 60 / (2 * math.pi)
    report["rpm_after"] = report["speeds"][-1][2] * 60 / (2 * math.pi)
    report["body"] = name
    sim.close()
    print(json.dumps(report))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
