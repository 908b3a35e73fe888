"""A live window (``taichi-dem run --window``): Taichi GGUI showing the particles (coloured by
speed, or temperature when thermal is on) and the bodies moving with their motion.

Keys: space pauses and resumes; up / down raise / lower the speed of the first rotating body
by 10 % (at least 1 rpm) through ``sim.set_speed``; Esc stops the run (the results so far
are kept). One output interval is simulated per drawn frame.

GGUI needs a display (and Vulkan); without one the CLI says so in one line and exits 2.
"""
from __future__ import annotations

import math
import os
import sys
from typing import Optional

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


def run_window(sim, until: float) -> None:
    """Show ``sim`` while it runs to ``until`` (s); returns when done or the window closes."""
    problem = display_problem()
    if problem:
        raise WindowError(problem)
    import taichi as ti
    from ..bodies.kinematics import rotation_matrix

    try:
        window = ti.ui.Window("taichi-dem", (1280, 800), vsync=True)
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

    driven = _first_rotating(sim)
    paused = False
    rpm = 60.0 / (2.0 * math.pi)
    while window.running and sim.time < until - 0.5 * sim.dt:
        for event in window.get_events(ti.ui.PRESS):
            if event.key == ti.ui.ESCAPE:
                return
            if event.key == " ":
                paused = not paused
            elif event.key in (ti.ui.UP, ti.ui.DOWN) and driven is not None:
                name = sim.scene.bodies[driven].name
                w = sim.engine.kinematics.speed(driven, sim.time)
                step = max(0.1 * abs(w), 1.0 / rpm)
                sim.set_speed(name, w + (step if event.key == ti.ui.UP else -step))
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
            scene.mesh(body_vertices[k], body_indices[k], color=(0.6, 0.6, 0.65), two_sided=True)
        canvas.scene(scene)
        gui = window.get_gui()
        with gui.sub_window("taichi-dem", 0.01, 0.01, 0.3, 0.16):
            gui.text(f"t = {sim.time:.3f} s   {'PAUSED' if paused else 'running'} (space)")
            if driven is not None:
                name = sim.scene.bodies[driven].name
                w = sim.engine.kinematics.speed(driven, sim.time)
                torque = sim.series.get(f"bodies/{name}/axial_torque")
                gui.text(f"{name}: {w * rpm:.1f} rpm (up/down)")
                if torque is not None and len(torque):
                    gui.text(f"axial torque {float(torque[-1]):.4g} N m")
        window.show()
