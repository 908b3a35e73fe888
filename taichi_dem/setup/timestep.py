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
from ..scene.keys import effect_sections
from ..scene.model import Scene

MIN_STEPS_PER_CONTACT = 20      # below this an impact is poorly resolved (auto dt avoids it)
ERROR_STEPS_PER_CONTACT = 8     # an explicit dt giving fewer is refused: restitution and
                                # overlap are then wrong by tens of percent, and it can diverge
MAX_RAYLEIGH_FRACTION = 0.5     # explicit dt beyond half the Rayleigh time is refused
BODY_STEP_FRACTION = 0.1        # auto dt: a body surface moves at most 0.1 r_min per step
BODY_STEP_ERROR = 0.3           # explicit dt moving a body surface more than 0.3 r_min per
                                # step is refused: a thin paddle could pass through a particle
# Physical sanity (issue 43): a step below MIN_DT, or a run of more than MAX_STEPS steps, is
# a scene that would run for years (1e10 steps are ~3 h at 1e6 steps/s for ONE particle; a
# real scene runs at 1e5 - 1e8 particle-steps/s), always a unit or property mistake
# (density 1e-25 gives dt 1.5e-19 s). Refused, naming the key that made it absurd.
MIN_DT = 1e-9                   # s
MAX_STEPS = 1e10
# A contact so soft that one particle's own weight presses it into its partner by more
# than its radius (Hertz: m g = 4/3 E* sqrt(R*) d^1.5, R* = r against a wall, the stiffest
# reading) is not a contact: particles pass through each other and the automatic step (set
# by the Hertz contact time) grows past the output interval or the whole run (E = 1e-3 Pa
# gives dt 0.22 s; density 1e25 gives 5,118 s; both ran "0 steps" and exited 0).
MAX_WEIGHT_OVERLAP = 1.0        # radii
# which material key to blame for an absurd step: the one furthest (in decades) from the
# range real granular solids (and their softened DEM stand-ins) occupy
PLAUSIBLE_DENSITY = (10.0, 3e4)            # kg/m^3: aerogel granules to tungsten
PLAUSIBLE_YOUNGS_MODULUS = (1e4, 1.2e12)   # Pa: soft gels (softened DEM) to diamond


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


def effect_bounds(scene: Scene) -> tuple[float, float, float]:
    """What the scene's effects can do to a free particle, as they declare it
    (scene/keys.py ``Section.work_bound``, ``acceleration_bound`` and ``speed_bound``): the
    work per unit mass their fields can do across the domain (J/kg; a directed field's along
    its direction, an undirected acceleration's along the domain's diagonal), the largest
    speed any carries one to (m/s), and the steady acceleration a resting particle bears
    (``resting_acceleration``, m/s^2: its weight)."""
    work = acceleration = speed = resting = 0.0
    sections = effect_sections()
    span = np.asarray(scene.domain.max) - np.asarray(scene.domain.min)
    for path, settings in scene.settings.items():
        section = sections[path]
        if section.work_bound is not None:
            work += float(section.work_bound(scene, settings, span))
        if section.acceleration_bound is not None:
            acceleration += float(section.acceleration_bound(scene, settings))
        if section.speed_bound is not None:
            speed = max(speed, float(section.speed_bound(scene, settings)))
        if section.resting_acceleration is not None:
            resting += float(section.resting_acceleration(scene, settings))
    work += acceleration * float(np.linalg.norm(span))
    return work, speed, resting


def expected_max_speed(scene: Scene, initial_speeds: np.ndarray) -> float:
    """Largest speed expected (m/s): the initial speeds; free fall across the domain under
    the effects' fields (gravity's along its direction, the others' along the domain's
    diagonal); the speed an effect carries a particle to; and the fastest body surface on
    top (a particle meets a moving paddle at both speeds)."""
    # the work per unit mass the fields can do across the domain bounds the kinetic energy
    work, carried, _ = effect_bounds(scene)
    fall = math.sqrt(2.0 * work)
    v0 = float(np.max(initial_speeds)) if len(initial_speeds) else 0.0
    return max(v0, fall, carried, 1e-3) + body_surface_speed(scene)


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
    rayleigh_material = contact_material = None
    for k, name in enumerate(material_names):
        sel = materials == k
        if not np.any(sel):
            continue
        mat = scene.materials[name]
        r = float(np.min(radii[sel]))
        if rayleigh_time(r, mat) < t_rayleigh:
            t_rayleigh, rayleigh_material = rayleigh_time(r, mat), name
        # the stiffest partner this material can meet (particles or walls)
        partners = (set(material_names[j] for j in np.unique(materials))
                    | {w.material for w in scene.walls} | {b.material for b in scene.bodies})
        for pname in partners:
            if frozenset((name, pname)) not in scene.interactions:
                continue
            e_eff = effective_youngs_modulus(mat, scene.materials[pname])
            m = 4.0 / 3.0 * math.pi * r ** 3 * mat.density
            # a small sphere against a wall: m* = m, R* = r (the shortest contact of this pair)
            if hertz_contact_time(m, r, e_eff, v) < t_contact:
                t_contact, contact_material = hertz_contact_time(m, r, e_eff, v), name
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
    report = TimeStepReport(dt, t_rayleigh, t_contact, v, courant, limited_by, notes)
    setter = {"rayleigh_fraction": rayleigh_material,
              "contact_duration": contact_material}.get(limited_by)
    refuse_absurd_step(scene, report, setter, radii, materials, material_names, fixed)
    return report


def _blamed_key(scene: Scene, material: str | None, too_small: bool) -> str:
    """The dotted key that made an automatic step absurd: the material property furthest
    (in decades) outside PLAUSIBLE_DENSITY / PLAUSIBLE_YOUNGS_MODULUS, in the direction that
    gives the fault (a tiny step: density too low or modulus too high; a huge one: the
    reverse); the material as a whole when neither stands out."""
    if material is None:
        return "simulation.dt"
    mat = scene.materials[material]
    lo_rho, hi_rho = PLAUSIBLE_DENSITY
    lo_e, hi_e = PLAUSIBLE_YOUNGS_MODULUS
    if too_small:      # dt ~ sqrt(rho / E): low density, high modulus
        off = {"density": math.log10(lo_rho / mat.density) if mat.density < lo_rho else 0.0,
               "youngs_modulus": (math.log10(mat.youngs_modulus / hi_e)
                                  if mat.youngs_modulus > hi_e else 0.0)}
    else:
        off = {"density": math.log10(mat.density / hi_rho) if mat.density > hi_rho else 0.0,
               "youngs_modulus": (math.log10(lo_e / mat.youngs_modulus)
                                  if mat.youngs_modulus < lo_e else 0.0)}
    worst = max(off, key=off.get)
    return f"materials.{material}.{worst}" if off[worst] > 0.0 else f"materials.{material}"


def _property_words(scene: Scene, material: str | None, radius: float,
                    which: str = "smallest radius") -> str:
    """' (material ...: density, modulus; radius)' for a message, '' without a material."""
    if material is None:
        return ""
    mat = scene.materials[material]
    return (f" (material {material!r}: density {mat.density:.3g} kg/m^3, Young's modulus "
            f"{mat.youngs_modulus:.3g} Pa; {which} {radius:.3g} m)")


def weight_overlap(scene: Scene, radii: np.ndarray, materials: np.ndarray,
                   material_names: list[str]) -> tuple[float, str | None, float]:
    """The largest overlap, in radii, that one particle's own weight presses into its
    softest partner (Hertz, m g = 4/3 E* sqrt(r) d^1.5, the particle's own radius as R*),
    over the materials present, with that material and radius (m); (0, None, nan) without
    gravity. Dimensionless."""
    g = effect_bounds(scene)[2]         # the weight per unit mass the effects give
    if g <= 0.0 or not len(radii):
        return 0.0, None, math.nan
    present = set(material_names[j] for j in np.unique(materials))
    partners = present | {w.material for w in scene.walls} | {b.material for b in scene.bodies}
    worst, worst_name, worst_radius = 0.0, None, math.nan
    for k, name in enumerate(material_names):
        sel = materials == k
        if not np.any(sel):
            continue
        mat = scene.materials[name]
        r = float(np.max(radii[sel]))       # the heaviest sphere of the material
        mass = 4.0 / 3.0 * math.pi * r ** 3 * mat.density
        for pname in partners:
            if frozenset((name, pname)) not in scene.interactions:
                continue
            e_eff = effective_youngs_modulus(mat, scene.materials[pname])
            depth = (3.0 * mass * g / (4.0 * e_eff * math.sqrt(r))) ** (2.0 / 3.0) / r
            if depth > worst:
                worst, worst_name, worst_radius = depth, name, r
    return worst, worst_name, worst_radius


def refuse_absurd_step(scene: Scene, report: TimeStepReport, setter: str | None,
                       radii: np.ndarray, materials: np.ndarray,
                       material_names: list[str], fixed: np.ndarray | None = None) -> None:
    """SceneError (file: key: reason) for a step no run can use (issue 43): below MIN_DT,
    more than MAX_STEPS to end_time, longer than the run or the output interval, a contact
    too soft to carry a particle's weight, or a step an effect cannot take (its
    ``Section.step_problem``: the damping's time constant). ``setter``: the material whose bound set an automatic step."""
    sim = scene.simulation
    dt = report.dt
    explicit = sim.dt is not None
    r_min = float(np.min(radii)) if len(radii) else math.nan
    if not (dt > 0.0 and math.isfinite(dt)):
        return           # describe_scene and the engine report a non-finite step themselves
    steps = sim.end_time / dt
    if dt < MIN_DT or steps > MAX_STEPS:
        key = "simulation.dt" if explicit else _blamed_key(scene, setter, too_small=True)
        if dt >= MIN_DT and key in ("simulation.dt", f"materials.{setter}"):
            key = "simulation.end_time"      # a sane step, an absurd duration
        origin = ("given" if explicit
                  else "automatic, set by the " + report.limited_by.replace("_", " "))
        raise SceneError(scene.source, key,
                         f"the time step is {dt:.3g} s ({origin})"
                         f"{'' if explicit else _property_words(scene, setter, r_min)}, "
                         f"and reaching end_time {sim.end_time:g} s takes {steps:.3g} steps: "
                         f"a run needs dt >= {MIN_DT:g} s and at most {MAX_STEPS:.0e} steps "
                         "(it would never finish; check the units of the density, modulus "
                         "and radii)")
    moving = fixed is None or not len(fixed) or not bool(np.all(fixed))
    depth, soft, heavy_radius = weight_overlap(scene, radii, materials, material_names)
    if depth > MAX_WEIGHT_OVERLAP and moving:
        key = _blamed_key(scene, soft, too_small=False)
        raise SceneError(scene.source, key if key != f"materials.{soft}" else
                         f"materials.{soft}.youngs_modulus",
                         f"a particle's own weight presses it {depth:.3g} radii into its "
                         f"partner{_property_words(scene, soft, heavy_radius, 'radius')}: "
                         f"more than {MAX_WEIGHT_OVERLAP:g} radius, the particles would pass "
                         f"through each other (the step would be {dt:.3g} s); the modulus is "
                         "too low or the density too high for a contact (check their units)")
    bound, what = min((sim.end_time, "simulation.end_time"),
                      (scene.output.interval, "output.interval"))
    if dt > bound:
        key = "simulation.dt" if explicit else _blamed_key(scene, setter, too_small=False)
        if key in (f"materials.{setter}", "simulation.dt") and not explicit:
            key = what        # plausible materials: the interval (or the run) is too short
        raise SceneError(scene.source, key,
                         f"the time step is {dt:.3g} s ({'given' if explicit else 'automatic'})"
                         f"{'' if explicit else _property_words(scene, setter, r_min)}, "
                         f"longer than {what} ({bound:g} s): the run could not resolve "
                         "anything (no sample, or steps coarser than the samples)")
    sections = effect_sections()
    for path, settings in scene.settings.items():
        # an effect's own limit on the step (Section.step_problem: the damping's time constant)
        check = sections[path].step_problem
        problem = check(settings, dt) if check is not None else None
        if problem:
            key, reason = problem
            raise SceneError(scene.source, f"{path}.{key}", reason)


# The cell grid (engine/grid.py) starts from cells one pair cutoff (at least 2 r_max) wide and
# coarsens until it holds at most 8 cells per particle; its first cell count is a 64-bit
# integer, so a domain more than ~2e6 cutoffs wide on each axis overflows it (OverflowError).
MAX_GRID_CELLS = 2.0 ** 62


def refuse_uncountable_grid(scene: Scene, radii: np.ndarray) -> None:
    """SceneError (key ``domain``) when the domain spans more pair cutoffs than a 64-bit cell
    count can number (``radii``: m; the cutoff is taken as 2 r_max, its least value)."""
    if not len(radii):
        return
    cutoff = 2.0 * float(np.max(radii))
    if not cutoff > 0.0:
        return
    span = np.asarray(scene.domain.max, float) - np.asarray(scene.domain.min, float)
    cells = float(np.prod(np.maximum(np.ceil(span / cutoff), 1.0)))
    if not cells <= MAX_GRID_CELLS:
        raise SceneError(scene.source, "domain",
                         f"the domain ({' x '.join(f'{x:.3g}' for x in span)} m) spans "
                         f"{cells:.3g} cells of the pair cutoff ({cutoff:.3g} m): more than "
                         f"the {MAX_GRID_CELLS:.3g} the cell grid can number; a smaller "
                         "domain (wrong units?)")


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
    refuse_uncountable_grid(scene, radii)
    if scene.simulation.skin:
        return report, scene.simulation.skin
    wanted = 2.0 * SKIN_REBUILD_STEPS * report.expected_speed * report.dt
    skin = min(max(wanted, SKIN_MIN_DIAMETERS * mean_diameter), SKIN_MAX_DIAMETERS * mean_diameter)
    report.courant_limit = skin / (2.0 * report.expected_speed)
    return report, skin
