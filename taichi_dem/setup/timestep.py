"""Choosing and checking the time step (PHYSICS.md, "Time step").

Three bounds: the Rayleigh time of the smallest particle (EDEM's criterion, the user's
``rayleigh_fraction``), the Hertz contact duration at the largest speed present (at least
``MIN_STEPS_PER_CONTACT`` steps per contact so the impact is resolved), and a DEM Courant
number U dt / skin, reported only: the engine checks every step whether any particle moved more
than half the skin since the last neighbour rebuild and rebuilds before computing forces, so
no contact is missed at any Courant number; a large one only means frequent rebuilds.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pair_tables import effective_youngs_modulus, hertz_contact_time, rayleigh_time
from ..errors import SceneError
from ..scene.model import Scene

MIN_STEPS_PER_CONTACT = 20      # below this an impact is poorly resolved (auto dt avoids it)
ERROR_STEPS_PER_CONTACT = 8     # an explicit dt giving fewer is refused: restitution and
                                # overlap are then wrong by tens of percent, and it can diverge
MAX_RAYLEIGH_FRACTION = 0.5     # explicit dt beyond half the Rayleigh time is refused
BODY_STEP_FRACTION = 0.1        # auto dt: a body surface moves at most 0.1 r_min per step
BODY_STEP_ERROR = 0.3           # explicit dt moving a body surface more than 0.3 r_min per
                                # step is refused: a thin paddle could pass through a particle


@dataclass
class TimeStepReport:
    dt: float                    # s, the step that will be used
    rayleigh_time: float         # s, of the smallest particle
    contact_time: float          # s, Hertz duration at the largest expected speed
    expected_speed: float        # m/s used for contact_time
    courant_limit: float         # s, skin / (2 v)
    limited_by: str              # which bound set dt
    notes: list[str]


def body_surface_speed(scene: Scene) -> float:
    """Largest speed of any point of any body over its whole speed schedule, m/s."""
    best = 0.0
    for b in scene.bodies:
        m = b.motion
        w = max((abs(p[1]) for p in m.speed.points), default=0.0) if m.speed else 0.0
        rel = np.asarray(b.vertices, float) - np.asarray(m.axis_point, float)
        axis = np.asarray(m.axis_direction, float)
        radial = rel - np.outer(rel @ axis, axis)
        reach = float(np.max(np.linalg.norm(radial, axis=1))) if len(rel) else 0.0
        best = max(best, w * reach + float(np.linalg.norm(m.velocity)))
    return best


def expected_max_speed(scene: Scene, initial_speeds: np.ndarray) -> float:
    """Largest speed expected: initial speeds, and free fall across the domain (m/s)."""
    g = float(np.linalg.norm(scene.simulation.gravity))
    span = np.asarray(scene.domain.max) - np.asarray(scene.domain.min)
    if g > 0:
        gdir = np.abs(np.asarray(scene.simulation.gravity)) / g
        # periodic axes do not bound a fall (a chute): cap those by the non-periodic span
        height = float(np.dot(gdir, span))
        fall = math.sqrt(2.0 * g * height)
    else:
        fall = 0.0
    v0 = float(np.max(initial_speeds)) if len(initial_speeds) else 0.0
    # a particle falling onto a moving paddle meets it at both speeds
    return max(v0, fall, 1e-3) + body_surface_speed(scene)


def choose_time_step(scene: Scene, radii: np.ndarray, materials: np.ndarray,
                     material_names: list[str], initial_speeds: np.ndarray,
                     skin: float, fixed: np.ndarray | None = None) -> TimeStepReport:
    """Automatic or checked explicit dt (s). Raises SceneError for an unstable explicit dt.
    Fixed particles never move, so when every particle is fixed (a heat-conduction test, a
    frozen bed) the mechanical bounds do not restrict an explicit dt."""
    notes: list[str] = []
    t_rayleigh = math.inf
    t_contact = math.inf
    v = expected_max_speed(scene, initial_speeds)
    for k, name in enumerate(material_names):
        sel = materials == k
        if not np.any(sel):
            continue
        mat = scene.materials[name]
        r = float(np.min(radii[sel]))
        t_rayleigh = min(t_rayleigh, rayleigh_time(r, mat))
        # the stiffest partner this material can meet (particles or walls)
        partners = (set(material_names[j] for j in np.unique(materials))
                    | {w.material for w in scene.walls} | {b.material for b in scene.bodies})
        for pname in partners:
            if frozenset((name, pname)) not in scene.interactions:
                continue
            e_eff = effective_youngs_modulus(mat, scene.materials[pname])
            m = 4.0 / 3.0 * math.pi * r ** 3 * mat.density
            # a small sphere against a wall: m* = m, R* = r (the shortest contact of this pair)
            t_contact = min(t_contact, hertz_contact_time(m, r, e_eff, v))
    if not math.isfinite(t_rayleigh):
        t_rayleigh = 1e-3
    courant = skin / (2.0 * v) if v > 0 else math.inf
    sim = scene.simulation
    r_min = float(np.min(radii)) if len(radii) else math.inf
    v_body = body_surface_speed(scene)
    if sim.dt is None:
        candidates = {"rayleigh_fraction": sim.rayleigh_fraction * t_rayleigh,
                      "contact_duration": t_contact / MIN_STEPS_PER_CONTACT}
        if v_body > 0:
            candidates["body_speed"] = BODY_STEP_FRACTION * r_min / v_body
        limited_by = min(candidates, key=candidates.get)
        dt = candidates[limited_by]
        if limited_by != "rayleigh_fraction":
            notes.append(f"dt reduced below {sim.rayleigh_fraction:g} x Rayleigh time by the "
                         f"{limited_by.replace('_', ' ')} bound")
    else:
        dt = sim.dt
        limited_by = "explicit"
        all_fixed = fixed is not None and len(fixed) and bool(np.all(fixed))
        if dt > MAX_RAYLEIGH_FRACTION * t_rayleigh and not all_fixed:
            raise SceneError(scene.source, "simulation.dt",
                             f"dt = {dt:g} s exceeds {MAX_RAYLEIGH_FRACTION:g} x the Rayleigh time "
                             f"{t_rayleigh:.3g} s of the smallest particle; the explicit "
                             f"integration is unstable. Use dt <= {0.2 * t_rayleigh:.3g} s "
                             f"(20 %) or dt = \"auto\"")
        if dt > t_contact / ERROR_STEPS_PER_CONTACT and not all_fixed:
            raise SceneError(scene.source, "simulation.dt",
                             f"dt = {dt:g} s resolves a contact at the expected {v:.3g} m/s "
                             f"(Hertz duration {t_contact:.3g} s) in fewer than "
                             f"{ERROR_STEPS_PER_CONTACT} steps; use dt <= "
                             f"{t_contact / MIN_STEPS_PER_CONTACT:.3g} s or dt = \"auto\"")
        if v_body > 0 and v_body * dt > BODY_STEP_ERROR * r_min:
            raise SceneError(scene.source, "simulation.dt",
                             f"dt = {dt:g} s lets a body surface moving at {v_body:.3g} m/s travel "
                             f"{v_body * dt / r_min:.2f} of the smallest radius per step; a thin "
                             f"paddle or flight could pass through a particle. Use dt <= "
                             f"{BODY_STEP_FRACTION * r_min / v_body:.3g} s or dt = \"auto\"")
        if dt > t_contact / MIN_STEPS_PER_CONTACT:
            notes.append(f"fewer than {MIN_STEPS_PER_CONTACT} steps per contact at {v:.3g} m/s")
    return TimeStepReport(dt, t_rayleigh, t_contact, v, courant, limited_by, notes)


SKIN_REBUILD_STEPS = 20          # default skin: a particle at the expected speed triggers a
                                 # neighbour rebuild at most every ~20 steps ...
SKIN_MIN_DIAMETERS = 0.1         # ... within 0.1 (LAMMPS's default for d = 1) and
SKIN_MAX_DIAMETERS = 0.5         # 0.5 mean diameters (more makes every list longer)


def choose_step_and_skin(scene: Scene, radii: np.ndarray, materials: np.ndarray,
                         material_names: list[str], initial_speeds: np.ndarray,
                         fixed: np.ndarray | None = None):
    """Time step report and Verlet skin (m). The skin is the scene's, or sized so a particle
    at the expected speed moves half of it in SKIN_REBUILD_STEPS steps: a bed cascading at
    metres per second (a drum) gets a larger skin than a slow dense flow. Measured on
    bench/mesh_drum.py: skin 0.1 d 5.3, 0.25 d 6.1, 0.5 d 7.2, 0.75 d 6.9 M particle-steps/s."""
    mean_diameter = 2.0 * float(np.mean(radii)) if len(radii) else 0.0
    provisional = scene.simulation.skin or SKIN_MIN_DIAMETERS * mean_diameter
    report = choose_time_step(scene, radii, materials, material_names, initial_speeds, provisional,
                              fixed)
    if scene.simulation.skin:
        return report, scene.simulation.skin
    wanted = 2.0 * SKIN_REBUILD_STEPS * report.expected_speed * report.dt
    skin = min(max(wanted, SKIN_MIN_DIAMETERS * mean_diameter), SKIN_MAX_DIAMETERS * mean_diameter)
    report.courant_limit = skin / (2.0 * report.expected_speed)
    return report, skin
