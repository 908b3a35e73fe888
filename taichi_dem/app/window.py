"""A live window (``taichi-dem run --window``): Taichi GGUI showing the particles (coloured by
speed, or temperature when thermal is on) and the bodies moving with their motion.

Keys: space pauses and resumes; up / down raise / lower the speed of the first rotating body
by 10 % (at least 1 rpm) through ``sim.set_speed``; w draws the bodies as wireframes (to see
the bed inside a closed drum) and back; Esc stops the run (the results so far are kept). One
output interval is simulated per drawn frame.

GGUI needs a display (and Vulkan); without one the CLI says so in one line and exits 2. With
no screen it runs under Xvfb with Mesa's software Vulkan driver (lavapipe; Debian packages
``xvfb`` and ``mesa-vulkan-drivers``): ``xvfb-run -s "-screen 0 1280x1024x24" taichi-dem run
SCENE --window``. tests/unit/test_window.py does that, takes screenshots and presses keys with
``xdotool``.
"""
from __future__ import annotations

import math
import os
import sys
from typing import Callable, Optional

import numpy as np

from ..errors import WindowError


def display_problem() -> Optional[str]:
    """Why no window can be opened here (one line), or None."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        return ("--window needs a display and this machine has none (DISPLAY and "
                "WAYLAND_DISPLAY are not set); run without --window, or record with "
                "--rrd FILE and open it in the rerun viewer")
    return None


def _first_rotating(sim) -> Optional[int]:
    for k, b in enumerate(sim.scene.bodies):
        if b.motion.speed is not None:
            return k
    return None


class Keys:
    """What the keys do: space pauses, up / down change the speed of the first rotating body
    by 10 % (at least 1 rpm), w toggles wireframe bodies, Esc stops. ``press(key)`` is what
    the window calls for each key pressed; it returns False for Esc."""

    def __init__(self, sim):
        self.sim = sim
        self.driven = _first_rotating(sim)
        self.paused = False
        self.wireframe = False

    def press(self, key: str) -> bool:
        import taichi as ti
        sim = self.sim
        if key == ti.ui.ESCAPE:
            return False
        if key == " ":
            self.paused = not self.paused
        elif key in ("w", "W"):
            self.wireframe = not self.wireframe
        elif key in (ti.ui.UP, ti.ui.DOWN) and self.driven is not None:
            name = sim.scene.bodies[self.driven].name
            w = sim.engine.kinematics.speed(self.driven, sim.time)
            step = max(0.1 * abs(w), 2.0 * math.pi / 60.0)
            sim.set_speed(name, w + (step if key == ti.ui.UP else -step))
        return True


def run_window(sim, until: float, *, size=(1280, 800), vsync: bool = True,
               on_frame: Optional[Callable] = None) -> None:
    """Show ``sim`` while it runs to ``until`` (s); returns when done, on Esc or when the
    window closes. ``on_frame(window, camera, frame, keys)``, if given, is called for every
    frame after it is drawn and before it is shown (the moment ``window.save_image`` and
    ``window.get_image_buffer_as_numpy`` capture it); it returns False to stop."""
    problem = display_problem()
    if problem:
        raise WindowError(problem)
    import taichi as ti
    from taichi_dem.geometry.mesh import rotation_matrix

    try:
        window = ti.ui.Window("taichi-dem", tuple(size), vsync=vsync)
    except Exception as err:  # noqa: BLE001  (GGUI reports a missing Vulkan in many ways)
        raise WindowError(f"--window: cannot open a GGUI window here ({str(err).splitlines()[0]}); "
                          f"run without --window, or record with --rrd FILE") from None
    canvas = window.get_canvas()
    scene = window.get_scene()
    camera = ti.ui.Camera()
    lo = np.asarray(sim.scene.domain.min, float)
    hi = np.asarray(sim.scene.domain.max, float)
    centre = 0.5 * (lo + hi)
    extent = float(np.linalg.norm(hi - lo))
    camera.position(*(centre + np.array([0.2, -1.0, 0.6]) * extent))
    camera.lookat(*centre)
    camera.up(0.0, 0.0, 1.0)

    capacity = sim.engine.state.capacity
    positions = ti.Vector.field(3, ti.f32, capacity)
    colours = ti.Vector.field(3, ti.f32, capacity)
    radii = ti.field(ti.f32, capacity)
    body_vertices, body_indices = [], []
    for b in sim.scene.bodies:
        v = ti.Vector.field(3, ti.f32, len(b.vertices))
        i = ti.field(ti.i32, 3 * len(b.faces))
        i.from_numpy(np.asarray(b.faces, np.int32).ravel())
        body_vertices.append(v)
        body_indices.append(i)

    keys = Keys(sim)
    driven = keys.driven
    rpm = 60.0 / (2.0 * math.pi)
    frame = 0
    while window.running and sim.time < until - 0.5 * sim.dt:
        for event in window.get_events(ti.ui.PRESS):
            if not keys.press(event.key):
                return
        paused = keys.paused
        if not paused:
            steps = min(sim.output_every, int(round((until - sim.time) / sim.dt)))
            sim.step(max(steps, 1))
        p = sim.particles()
        n = len(p["id"])
        pos = np.zeros((capacity, 3), np.float32)
        pos[:n] = p["position"]
        rad = np.zeros(capacity, np.float32)
        rad[:n] = p["radius"]
        value = p["temperature"] if "temperature" in p else np.linalg.norm(p["velocity"], axis=1)
        span = float(np.ptp(value)) or 1.0
        u = (value - float(np.min(value))) / span
        col = np.zeros((capacity, 3), np.float32)
        col[:n] = np.stack([u, 0.3 + 0.4 * (1 - abs(2 * u - 1)), 1 - u], axis=1)
        positions.from_numpy(pos)
        radii.from_numpy(rad)
        colours.from_numpy(col)
        camera.track_user_inputs(window, movement_speed=0.01 * extent, hold_key=ti.ui.RMB)
        scene.set_camera(camera)
        scene.ambient_light((0.4, 0.4, 0.4))
        scene.point_light(pos=tuple(centre + np.array([0, 0, 2 * extent])), color=(1, 1, 1))
        scene.particles(positions, radius=float(np.mean(p["radius"])), per_vertex_color=colours,
                        per_vertex_radius=radii, index_count=n)
        kin = getattr(sim.engine, "kinematics", None)
        for k, b in enumerate(sim.scene.bodies):
            m = b.motion
            rot = rotation_matrix(np.asarray(m.axis_direction, float), kin.angle(k, sim.time))
            ap = np.asarray(m.axis_point, float)
            v = (b.vertices - ap) @ rot.T + ap + np.asarray(m.velocity, float) * sim.time
            body_vertices[k].from_numpy(v.astype(np.float32))
            scene.mesh(body_vertices[k], body_indices[k], color=(0.6, 0.6, 0.65), two_sided=True,
                       show_wireframe=keys.wireframe)
        canvas.scene(scene)
        gui = window.get_gui()
        with gui.sub_window("taichi-dem", 0.01, 0.01, 0.3, 0.16):
            gui.text(f"t = {sim.time:.3f} s   {'PAUSED' if paused else 'running'} (space; "
                     f"w: wireframe)")
            if driven is not None:
                name = sim.scene.bodies[driven].name
                w = sim.engine.kinematics.speed(driven, sim.time)
                torque = sim.series.get(f"bodies/{name}/axial_torque")
                gui.text(f"{name}: {w * rpm:.1f} rpm (up/down)")
                if torque is not None and len(torque):
                    gui.text(f"axial torque {float(torque[-1]):.4g} N m")
        if on_frame is not None and on_frame(window, camera, frame, keys) is False:
            return
        window.show()
        frame += 1
