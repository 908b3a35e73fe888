"""The map of a machine from periodic axial slices (issue 31 item 1): a drum or paddle-cooler
slice, periodic along its axis, filled to a set hold-up and run until its transport, torque and
heat reach a statistical steady state; over several hold-ups, the table a whole machine is
assembled from (the march along the axis: at each position the hold-up that carries the feed).

What a slice reports at each output sample (``SliceObserver``), per metre of machine where it
scales with length:

axial_mass_flow      kg/s   sum m v_a / L: the mass crossing a cross-section per second
axial_speed          m/s    sum m v_a / sum m, the bed's mean axial speed
<body>/torque_per_metre  N m/m  the axial torque the particles exert on the body, / L
<body>/power_per_metre   W/m    the drive power that torque takes at the body's speed, / L
<body>/covered_area_per_metre, <body>/heat_transfer_coefficient: for an isothermal body
shell_layer_axial_speed m/s the axial speed of the layer on the shell (Saeman's passive bed has
                            none: a layer creeping along the shell carries more than Saeman)
slip_ratio           -      the tangential speed of the layer on the shell over the shell's at
                            the same radius (1: the bed rides with the shell; a smooth shell's
                            bed rolls like a bearing at ~0.5); NaN for a shell at rest
dynamic_angle        deg    the slope of the bed's free surface across the section, against
                            gravity's component in it
surface_chord        m      the length of that surface across the shell (Saeman's c), through
                            the top layer's centres
axial_dispersion     m^2/s  D_ax: half the growth rate of the variance of the particles' unwrapped
                            axial displacements (app/dispersion.py), from the flow's steady start
airborne_fraction    -      the mass fraction touching nothing, in flight (app/curtains.py)
airborne_mass_flow   kg/s   the part of axial_mass_flow those particles carry in flight (the
                            curtains' share of the transport; the rest rides the bed and flights)
curtain_area_per_metre m^2/m those particles' surface per metre: what a dryer's gas meets
curtain_slip_speed   m/s    their mean speed relative to the gas ([gas] velocity; at rest without)
surface_area_per_metre m^2/m the other particles' surface open to the gas (the bed's top and the
                            flights' loads: app/curtains.py exposed_fraction), per metre; in a
                            slice with a [gas]
surface_slip_speed   m/s    its area-weighted mean speed relative to the gas

``map_slices`` runs a scene at each hold-up (kg/m, or a fill fraction of the free section at
a bulk solid fraction of BULK_SOLID_FRACTION) and reduces each series to its steady mean and
standard error (app/steady_state.py: MSER-5 for the start, blocking for the error).
``taichi-dem map`` writes the table (CSV, Markdown, JSON) and a plot.
"""
from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SceneError
from .machine import parse_holdup, saeman_check
from .steady_state import steady_mean

# bulk solid fraction of a sheared bed of spheres (random loose to random close packing is 0.55 -
# 0.64; a rolling drum bed ~0.58 - 0.60): converts a fill fraction of the free section to kg/m
BULK_SOLID_FRACTION = 0.6
# the layer on the shell whose speed is compared with the shell's: centres within this many
# radii of the shell
SHELL_LAYER_RADII = 2.0
# a bed whose layer on the shell moves at less than this fraction of the shell's speed slips
SLIP_BELOW = 0.9


@dataclass(frozen=True)
class SliceGeometry:
    """A periodic slice: its ``axis`` index (0, 1, 2 for x, y, z), ``length`` L (m), the
    rotation axis (``axis_point`` m, ``axis_direction`` unit), the ``shell`` body's index and
    radius (m: the largest distance of its vertices from the axis), the free cross-section
    ``free_area`` (m^2: the shell's circle less what the other bodies fill, their convex
    cross-section bounded by their radial extent at the shaft: pi r_shaft^2)."""
    axis: int
    length: float
    axis_point: np.ndarray
    axis_direction: np.ndarray
    shell: int
    shell_radius: float
    free_area: float


def _radial(points: np.ndarray, point: np.ndarray, direction: np.ndarray) -> np.ndarray:
    rel = points - point
    return np.linalg.norm(rel - np.outer(rel @ direction, direction), axis=1)


def slice_geometry(scene) -> SliceGeometry:
    """The slice's geometry, or a SceneError (file: key: reason) when the scene is not a
    periodic slice: one periodic axis, along which every body turns and which every body spans
    (a body shorter than the period does not repeat across the periodic faces), no factories
    or outlets (a slice holds its hold-up), and a particle fill to set the hold-up with."""
    src = scene.source
    if len(scene.domain.periodic) != 1:
        raise SceneError(src, "domain.periodic", "a slice is periodic along its axis only "
                         f"(one axis), this scene along {list(scene.domain.periodic) or 'none'}")
    axis = "xyz".index(scene.domain.periodic[0])
    length = float(scene.domain.max[axis] - scene.domain.min[axis])
    unit = np.zeros(3)
    unit[axis] = 1.0
    if not scene.bodies:
        raise SceneError(src, "bodies", "a slice needs a shell (a mesh body around the axis)")
    for key, items in (("factories", scene.factories), ("outlets", scene.outlets)):
        if items:
            raise SceneError(src, key, "a slice holds its hold-up: no inlet or outlet (the map "
                             "sets the hold-up; the march adds the feed)")
    if not scene.fills:
        raise SceneError(src, "particles", "a slice needs a particle fill to set the hold-up of")
    point = np.asarray(scene.bodies[0].motion.axis_point, float)
    for b in scene.bodies:
        direction = np.asarray(b.motion.axis_direction, float)
        if abs(abs(direction @ unit) - 1.0) > 1e-6:
            raise SceneError(src, f"{b.key}.motion", f"body {b.name!r} turns about "
                             f"{direction.tolist()}, not the periodic axis "
                             f"{scene.domain.periodic[0]}")
        extent = float(np.ptp(b.vertices[:, axis])) if len(b.vertices) else 0.0
        if extent < length * (1.0 - 1e-6):
            raise SceneError(src, f"{b.key}.mesh", f"body {b.name!r} spans {extent:.6g} m of "
                             f"the {length:.6g} m period along {scene.domain.periodic[0]}: it does "
                             "not repeat across the periodic faces (make it as long as the period)")
    radii = [float(np.max(_radial(b.vertices, point, unit))) for b in scene.bodies]
    shell = int(np.argmax(radii))
    shell_radius = radii[shell]
    # what the other bodies take from the section: a shaft's core (the smallest radial
    # extent of its vertices near the axis is its surface; paddles are thin and not counted)
    taken = 0.0
    for k, b in enumerate(scene.bodies):
        if k == shell:
            continue
        r = _radial(b.vertices, point, unit)
        taken += math.pi * float(np.min(r[r > 1e-9])) ** 2 if np.any(r > 1e-9) else 0.0
    free = math.pi * shell_radius ** 2 - taken
    return SliceGeometry(axis, length, point, unit, shell, shell_radius, free)




def fill_particle_mass(scene, fill_index: int = 0) -> float:
    """The mean mass (kg) of a particle of fill ``fill_index``: from its radius (the mean of a
    distribution: its mean r^3 for a normal law is r^3 (1 + 3 (s/r)^2), kept) and density."""
    fill = scene.fills[fill_index]
    if fill.radius is None:
        radii = fill.radii
        r3 = float(np.mean(radii ** 3)) if radii is not None and len(radii) else 0.0
    else:
        mean, std = fill.radius.mean, fill.radius.std
        r3 = mean ** 3 * (1.0 + 3.0 * (std / mean) ** 2)
    return 4.0 / 3.0 * math.pi * r3 * scene.materials[fill.material].density


def holdup_count(scene, geometry: SliceGeometry, holdup: tuple[str, float],
                 fill_index: int = 0) -> tuple[int, float, float]:
    """(particles, hold-up kg/m, fill fraction) for ``holdup`` (parse_holdup's), or a
    SceneError when the free section cannot hold it at BULK_SOLID_FRACTION."""
    kind, value = holdup
    fill = scene.fills[fill_index]
    density = scene.materials[fill.material].density
    per_metre_full = density * BULK_SOLID_FRACTION * geometry.free_area     # kg/m at fill 1
    kg_per_m = value if kind == "kg/m" else value * per_metre_full
    fraction = kg_per_m / per_metre_full
    if not 0.0 < fraction <= 1.0:
        raise SceneError(scene.source, f"{fill.key}.count",
                         f"a hold-up of {kg_per_m:.4g} kg/m is a fill fraction of {fraction:.3g}: "
                         f"the free section ({geometry.free_area:.4g} m^2) holds at most "
                         f"{per_metre_full:.4g} kg/m at a bulk solid fraction of "
                         f"{BULK_SOLID_FRACTION}")
    count = int(round(kg_per_m * geometry.length / fill_particle_mass(scene, fill_index)))
    return max(count, 1), kg_per_m, fraction


class SliceObserver:
    """Observer (Simulation.add_observer) recording a slice's figures at each sample."""

    def __init__(self, sim, geometry: SliceGeometry, shell_mesh: dict | None = None):
        self.g = geometry
        self.scene = sim.scene
        gravity = np.asarray(sim.scene.simulation.gravity, float)
        a = geometry.axis_direction
        across = gravity - (gravity @ a) * a
        self.up = -across / np.linalg.norm(across) if np.linalg.norm(across) > 0 else np.array([0, 0, 1.0])
        self.horizontal = np.cross(self.up, a)
        self.series: dict[str, list] = {}
        # each particle's unwrapped axial displacement: the axial dispersion (dispersion.py)
        from .dispersion import AxialDisplacements
        self.displacements = AxialDisplacements(geometry.length)
        # the curtains (curtains.py): the bodies' meshes at their t = 0 placement, and the gas
        # the particles fall through (a [gas] section's velocity; at rest without one)
        import trimesh
        self.meshes = [trimesh.Trimesh(np.asarray(b.vertices, float), np.asarray(b.faces),
                                       process=False) for b in sim.scene.bodies]
        gas = sim.scene.settings.get("gas")
        self.gas_velocity = tuple(getattr(gas, "velocity", (0.0, 0.0, 0.0)))
        # the flights' loads against their angle (flights.py), for a drum builder's flights
        from .flights import FlightRecorder
        self.flights = (FlightRecorder.for_slice(sim, geometry, shell_mesh, self.up,
                                                 self.horizontal) if shell_mesh else None)
        # the surface the gas sweeps besides the curtains: a dryer's figure, measured in a
        # slice with a [gas] (~0.13 s a sample for 1,500 particles in a flighted drum, ~5 %
        # of such a slice's time)
        self.surface = gas is not None

    def _add(self, name: str, value: float):
        self.series.setdefault(name, []).append(float(value))

    def __call__(self, sim, values: dict):
        g = self.g
        p = sim.particles()
        moving = ~p["fixed"]
        x, v, m, r = p["position"][moving], p["velocity"][moving], p["mass"][moving], p["radius"][moving]
        self._add("time", values.get("time", sim.time))
        self.displacements.add(values.get("time", sim.time), x @ g.axis_direction)
        axial = v @ g.axis_direction
        self._add("axial_mass_flow", float(np.sum(m * axial)) / g.length)
        self._add("axial_speed", float(np.sum(m * axial) / np.sum(m)) if len(m) else math.nan)
        shell = self.scene.bodies[g.shell]
        omega = float(values.get(f"bodies/{shell.name}/angular_speed", 0.0))
        self._add("slip_ratio", slip_ratio(x, v, r, g, omega))
        self._add("shell_layer_axial_speed", shell_layer_axial_speed(x, v, r, g))
        slope, offset = bed_surface(x, r, g.axis_point, self.horizontal, self.up)
        self._add("dynamic_angle", math.degrees(math.atan(abs(slope))) if math.isfinite(slope)
                  else math.nan)
        # the surface through the top layer's centres (the tops less a mean radius): the
        # chord Saeman's flow is computed from, measured rather than from an assumed packing
        self._add("surface_chord", surface_chord(slope, offset - float(np.mean(r)) if len(r)
                                                 else math.nan, g.shell_radius))
        poses = sim.body_poses()
        from .curtains import airborne, curtain_figures
        placed = [poses[b.name] for b in self.scene.bodies]
        free = airborne(x, r, self.meshes, placed, g.length, g.axis)
        for name, value in curtain_figures(x, v, r, m, self.meshes, placed, g.length, g.axis,
                                           self.gas_velocity, free=free,
                                           surface=self.surface,
                                           axis_direction=g.axis_direction).items():
            self._add(name, value)
        if self.flights is not None:
            self.flights.sample(x, m, ~free, placed[g.shell][0])
        for body in self.scene.bodies:
            prefix = f"bodies/{body.name}/"
            for name, out in (("axial_torque", "torque_per_metre"), ("power", "power_per_metre"),
                              ("covered_area", "covered_area_per_metre")):
                if prefix + name in values:
                    self._add(f"{body.name}/{out}", float(values[prefix + name]) / g.length)
            if prefix + "heat_transfer_coefficient" in values:
                self._add(f"{body.name}/heat_transfer_coefficient",
                          float(values[prefix + "heat_transfer_coefficient"]))
            if prefix + "heat_flow" in values and body.temperature is not None:
                # the wall's conductance per metre, U' = Q / (L (T_bed - T_wall)) (W/(m K)): what
                # the march cools the bed with (a real heat flow over the bed's mean temperature
                # difference; a thermal time scale lowers it, the wall layer drained faster
                # than the mixing renews it: app/machine.py)
                difference = values.get("particles/mean_temperature", math.nan) - body.temperature
                self._add(f"{body.name}/conductance_per_metre",
                          float(values[prefix + "heat_flow"]) / (g.length * difference)
                          if difference and math.isfinite(difference) else math.nan)


def slip_ratio(position, velocity, radius, geometry: SliceGeometry, omega: float) -> float:
    """Mean tangential speed of the particles whose centres lie within SHELL_LAYER_RADII radii
    of the shell, over the shell's speed at their radius (omega r, rad/s x m); NaN for a shell
    at rest or no particle there."""
    if omega == 0.0 or len(position) == 0:
        return math.nan
    a = geometry.axis_direction
    rel = position - geometry.axis_point
    radial = rel - np.outer(rel @ a, a)
    r = np.linalg.norm(radial, axis=1)
    near = r > geometry.shell_radius - SHELL_LAYER_RADII * radius
    near &= r > 0.0
    if not np.any(near):
        return math.nan
    tangent = np.cross(a, radial[near] / r[near, None])
    return float(np.mean(np.sum(velocity[near] * tangent, axis=1)) / (omega * np.mean(r[near])))


def shell_layer_axial_speed(position, velocity, radius, geometry: SliceGeometry) -> float:
    """Mean axial speed (m/s) of the particles whose centres lie within SHELL_LAYER_RADII radii
    of the shell: Saeman's bed moves along the axis only in its surface layer; a layer on the
    shell creeping along it (spheres rolling down the incline between lifters) carries more.
    NaN with nothing there."""
    a = geometry.axis_direction
    rel = position - geometry.axis_point
    r = np.linalg.norm(rel - np.outer(rel @ a, a), axis=1)
    near = r > geometry.shell_radius - SHELL_LAYER_RADII * radius
    return float(np.mean(velocity[near] @ a)) if np.any(near) else math.nan


def bed_surface(position, radius, axis_point, horizontal, up, bins: int = 12):
    """The bed's free surface across the section as a line up = slope h + offset (m, about
    the axis): the section is cut into ``bins`` strips across (along ``horizontal``), the
    surface in each is its highest particle top (along ``up``), and a line is fitted through
    the inner two thirds of the strips the bed occupies (the toe and the shoulder curve).
    (nan, nan) with fewer than 3 strips."""
    if len(position) < 3:
        return math.nan, math.nan
    rel = position - axis_point
    h = rel @ horizontal
    top = rel @ up + radius
    edges = np.linspace(h.min(), h.max(), bins + 1)
    which = np.clip(np.digitize(h, edges) - 1, 0, bins - 1)
    centres, heights = [], []
    for k in range(bins):
        sel = which == k
        if np.any(sel):
            centres.append(0.5 * (edges[k] + edges[k + 1]))
            heights.append(float(np.max(top[sel])))
    n = len(centres)
    cut = n // 6
    centres, heights = np.array(centres[cut:n - cut]), np.array(heights[cut:n - cut])
    if len(centres) < 3:
        return math.nan, math.nan
    slope, offset = np.polyfit(centres, heights, 1)
    return float(slope), float(offset)


def dynamic_angle(position, radius, axis_point, horizontal, up, bins: int = 12) -> float:
    """The free surface's slope across the section (degrees, 0 - 90; bed_surface's line)."""
    slope, _ = bed_surface(position, radius, axis_point, horizontal, up, bins)
    return float(math.degrees(math.atan(abs(slope)))) if math.isfinite(slope) else math.nan


def surface_chord(slope: float, offset: float, shell_radius: float) -> float:
    """The length (m) of the bed's surface line (bed_surface) across a shell of
    ``shell_radius``: 2 sqrt(R^2 - p^2), p the line's distance from the axis (Saeman's c)."""
    if not (math.isfinite(slope) and math.isfinite(offset)):
        return math.nan
    p = abs(offset) / math.sqrt(1.0 + slope * slope)
    return 2.0 * math.sqrt(max(shell_radius ** 2 - p * p, 0.0))


@dataclass
class SliceResult:
    """One hold-up of the map: what was set and each figure's steady mean (app/steady_state)."""
    holdup: float            # kg/m
    fill_fraction: float
    particles: int
    figures: dict            # name -> SteadyMean
    incline: float = 0.0     # deg, the +axis end raised (gravity's axial pull towards -axis)
    axial_slope: float = 0.0 # gravity's axial component / its component in the section
    flight_unloading: dict | None = None   # flights.unloading_profile, for a flighted drum

    def row(self) -> dict:
        out = {"holdup_kg_per_m": self.holdup, "fill_fraction": self.fill_fraction,
               "particles": self.particles, "incline_deg": self.incline,
               "axial_slope": self.axial_slope}
        for name, m in self.figures.items():
            out[name] = m.mean
            out[name + "_standard_error"] = m.standard_error
            out[name + "_steady"] = m.steady
        slip = self.figures.get("slip_ratio")
        out["slips"] = bool(slip is not None and math.isfinite(slip.mean) and slip.mean < SLIP_BELOW)
        return out


# the figures a map reports (units), in table order; bodies' figures follow
FIGURES = {"axial_mass_flow": "kg/s", "axial_speed": "m/s", "slip_ratio": "-",
           "shell_layer_axial_speed": "m/s", "surface_chord": "m", "bed_solid_fraction": "-",
           "dynamic_angle": "deg", "saeman_flow": "kg/s", "saeman_ratio": "-",
           "axial_dispersion": "m^2/s", "airborne_fraction": "-", "airborne_mass_flow": "kg/s",
           "curtain_area_per_metre": "m^2/m", "curtain_slip_speed": "m/s",
           "surface_area_per_metre": "m^2/m", "surface_slip_speed": "m/s"}
BODY_FIGURES = {"torque_per_metre": "N m/m", "power_per_metre": "W/m",
                "covered_area_per_metre": "m^2/m", "heat_transfer_coefficient": "W/(m^2 K)",
                "conductance_per_metre": "W/(m K)"}


def incline_of(gravity, geometry: SliceGeometry) -> tuple[float, float]:
    """(incline deg, axial slope) of ``gravity``: the incline raises the +axis end (gravity's
    axial component towards -axis is positive incline), the axial slope is gravity's axial
    component over its component in the section (tan of minus the incline)."""
    g = np.asarray(gravity, float)
    along = float(g @ geometry.axis_direction)
    across = float(np.linalg.norm(g - along * geometry.axis_direction))
    slope = along / across if across > 0.0 else math.copysign(math.inf, along)
    return -math.degrees(math.atan(slope)), slope


def inclined_gravity(gravity, geometry: SliceGeometry, incline_deg: float) -> list:
    """``gravity`` turned about the section so that the +axis end is raised ``incline_deg``:
    the same magnitude, the same direction across the section (straight down when it had none)."""
    g = np.asarray(gravity, float)
    a = geometry.axis_direction
    across = g - (g @ a) * a
    down = across / np.linalg.norm(across) if np.linalg.norm(across) > 0 else -np.eye(3)[
        2 if geometry.axis != 2 else 1]
    t = math.radians(incline_deg)
    new = float(np.linalg.norm(g)) * (math.cos(t) * down - math.sin(t) * a)
    return [float(v) for v in new]


def machine_info(scene, geometry: SliceGeometry, fill_index: int = 0) -> dict:
    """What the march (app/machine.py) needs of the slice: the section (shell radius, shaft
    radius, bulk density at BULK_SOLID_FRACTION), the mean particle diameter, the period, the
    bodies' names, angular speeds (rad/s) and wall temperatures (K, isothermal bodies) and the
    bed material's heat capacity (J/(kg K), thermal scenes)."""
    fill = scene.fills[fill_index]
    material = scene.materials[fill.material]
    shaft_area = math.pi * geometry.shell_radius ** 2 - geometry.free_area
    mass = fill_particle_mass(scene, fill_index)
    diameter = 2.0 * (3.0 * mass / (4.0 * math.pi * material.density)) ** (1.0 / 3.0)
    speeds, walls = {}, {}
    for b in scene.bodies:
        sched = b.motion.speed
        speeds[b.name] = float(sched.at(0.0)) if sched is not None else 0.0
        if b.temperature is not None:
            walls[b.name] = float(b.temperature)
    return {"shell_radius": geometry.shell_radius,
            "shaft_radius": math.sqrt(max(shaft_area, 0.0) / math.pi),
            "bulk_density": material.density * BULK_SOLID_FRACTION,
            "particle_diameter": diameter, "period": geometry.length,
            "axis": "xyz"[geometry.axis], "bodies": [b.name for b in scene.bodies],
            "shell": scene.bodies[geometry.shell].name,
            "angular_speeds": speeds, "wall_temperatures": walls,
            "heat_capacity": (getattr(material, "heat_capacity", None)
                              if scene.settings.get("thermal") is not None else None),
            # the gas the curtains fell through ([gas]: axial speed m/s, density kg/m^3; a dryer
            # marched on the map should blow as fast) and whether it was forced through the bed
            "gas": ({"axial_velocity": float(np.asarray(gas.velocity, float) @ geometry.axis_direction),
                     "density": float(gas.density),
                     "through_bed": bool(gas.through_bed)}
                    if (gas := scene.settings.get("gas")) is not None else None)}


def run_slice(text: str, source: str, holdup: tuple[str, float], duration: float,
              fill_index: int = 0, base_dir=None, arch: str = "cpu",
              incline: float | None = None, threads: int | None = None,
              picture: str | None = None) -> SliceResult:
    """Build the slice of scene ``text`` at ``holdup`` (and ``incline`` deg, the +axis end
    raised; None: the scene's gravity), run it ``duration`` s, and reduce each sampled figure
    to its steady mean. ``threads``: CPU threads (None: all cores); ``picture``: a PNG of the
    bed's cross-section at the end (slice_picture.py)."""
    from ..run.simulation import Simulation
    from ..scene.loader import parse_scene
    from .overrides import apply, to_text
    scene = parse_scene(text, source=source, base_dir=base_dir)
    geometry = slice_geometry(scene)
    count, kg_per_m, fraction = holdup_count(scene, geometry, holdup, fill_index)
    changes = {f"particles.{fill_index}.count": count}
    if incline is not None:
        changes["simulation.gravity"] = inclined_gravity(scene.simulation.gravity, geometry,
                                                         incline)
    doc = apply(tomllib.loads(text), changes, source)
    sliced = parse_scene(to_text(doc), source=source, base_dir=base_dir)
    angle, slope = incline_of(sliced.simulation.gravity, geometry)
    shell_mesh = (doc.get("bodies") or [{}])[geometry.shell].get("mesh") \
        if len(doc.get("bodies") or []) > geometry.shell else None
    with Simulation(sliced, arch=arch, h5="", threads=threads) as sim:
        observer = SliceObserver(sim, geometry, shell_mesh if isinstance(shell_mesh, dict) else None)
        sim.add_observer(observer, now=False)
        sim.run(sim.time + duration)
        series = observer.series
        if picture:
            from .slice_picture import draw_bed
            draw_bed(sim, geometry, observer.up, observer.horizontal, Path(picture),
                     f"{Path(source).name}: {kg_per_m:.4g} kg/m ({100 * fraction:.0f} % "
                     f"full), {angle:.3g} deg, t = {sim.time:.3g} s")
    # (a figure undefined at some samples - a slip ratio with nothing on the shell - is
    # reduced over the samples where it is defined)
    figures = {}
    for name, values in series.items():
        finite = np.asarray(values, float)
        finite = finite[np.isfinite(finite)]
        if name != "time" and len(finite) >= 2:
            figures[name] = steady_mean(finite)
    dispersion = _axial_dispersion(observer.displacements, figures.get("axial_mass_flow"))
    if dispersion is not None:
        figures["axial_dispersion"] = dispersion
    unloading = None
    if observer.flights is not None:
        steady = figures.get("airborne_fraction") or figures.get("axial_mass_flow")
        start = steady.start if steady is not None else len(series.get("time", [])) // 2
        # the flights' loads as cross-sections of the bulk at the map's packing
        density = sliced.materials[sliced.fills[fill_index].material].density * BULK_SOLID_FRACTION
        unloading = observer.flights.profile(geometry.length, density, start)
    return SliceResult(kg_per_m, fraction, count, figures, angle, slope, unloading)


def _axial_dispersion(record, flow):
    """D_ax (m^2/s) as a SteadyMean: the variance growth of the axial displacements from the
    flow's steady start on (dispersion.dispersion_coefficient); None when too short."""
    from .dispersion import dispersion_coefficient
    from .steady_state import SteadyMean
    start = flow.start if flow is not None else len(record.times) // 2
    times, variances = record.times[start:], record.variances[start:]
    if len(times) < 12:
        return None
    value, error = dispersion_coefficient(times, variances)
    if not math.isfinite(value):
        return None
    return SteadyMean(value, error, start, len(times), max(len(times) // 4, 1), 4, True,
                      bool(flow.steady) if flow is not None else False)


def write_map(results: list[SliceResult], out_dir: Path, scene_name: str,
              machine: dict | None = None) -> list[Path]:
    """map.csv, map.md, map.json and map.png (torque per metre and axial mass flow against
    hold-up) in ``out_dir``, the rows in hold-up order within each incline (inclines in the
    order they first appear); returns their paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    # SliceResults, or rows already written (a map being added to: --add)
    rows = [r.row() if isinstance(r, SliceResult) else dict(r) for r in results]
    order = list(dict.fromkeys(round(r["incline_deg"], 6) for r in rows))
    rows.sort(key=lambda r: (order.index(round(r["incline_deg"], 6)), r["holdup_kg_per_m"]))
    if machine:
        for row in rows:
            flow, ratio = saeman_check(row, machine)
            if math.isfinite(flow):
                # Saeman's uniform-bed flow at the measured dynamic angle, and the map's over it
                row["saeman_flow"], row["saeman_ratio"] = flow, ratio
            chord = row.get("surface_chord", math.nan)
            R = machine["shell_radius"]
            if math.isfinite(chord) and 0.0 < chord < 2.0 * R:
                from .machine import Section
                section = Section(R, machine.get("shaft_radius", 0.0), 1.0)
                # a chord lies at two depths, below the axis and above it: the one whose
                # section holds the hold-up nearer the bulk density (a bed over half full
                # stands above the axis)
                half = math.sqrt(R * R - 0.25 * chord * chord)
                needed = row["holdup_kg_per_m"] / machine["bulk_density"]
                depth = min((R - half, R + half),
                            key=lambda d: abs(float(section.area(d)) - needed))
                area = float(section.area(depth))
                density = machine["bulk_density"] / BULK_SOLID_FRACTION
                # the bed's solid fraction under its measured surface
                row["bed_solid_fraction"] = row["holdup_kg_per_m"] / (density * area)
    names = list(dict.fromkeys(k for row in rows for k in row))
    csv = out_dir / "map.csv"
    with open(csv, "w") as f:
        f.write(",".join(names) + "\n")
        for row in rows:
            f.write(",".join(_cell(row.get(n, "")) for n in names) + "\n")
    md = out_dir / "map.md"
    figures = [n for n in names if not n.endswith(("_standard_error", "_steady"))
               and n not in ("holdup_kg_per_m", "fill_fraction", "particles", "slips",
                             "incline_deg", "axial_slope")]
    lines = [f"# Map of {scene_name}: steady means +- standard error", "",
             "| incline (deg) | hold-up (kg/m) | fill | particles | " + " | ".join(
                 f"{n} ({_unit(n)})" for n in figures) + " | slips |",
             "|---" * (len(figures) + 5) + "|"]
    for row in rows:
        cells = [f"{row['incline_deg']:.3g}", f"{row['holdup_kg_per_m']:.4g}",
                 f"{row['fill_fraction']:.3f}", str(row["particles"])]
        for n in figures:
            mean, se = row.get(n), row.get(n + "_standard_error")
            flag = "" if row.get(n + "_steady", True) else " (not steady)"
            if mean is None:
                cells.append("")
            elif se is None:
                cells.append(f"{mean:.4g}")
            else:
                cells.append(f"{mean:.4g} +- {se:.2g}{flag}")
        cells.append("yes" if row["slips"] else "no")
        lines.append("| " + " | ".join(cells) + " |")
    beds = sorted(out_dir.glob("bed_*.png"))         # map --pictures: the beds at the end
    if beds:
        lines += ["", "The beds at the end of their runs (`--pictures`), seen along the axis, "
                  "coloured by axial speed:", ""]
        lines += [f"![{png.stem}]({png.name})" for png in beds]
    unloading = [(r.holdup, r.incline, r.flight_unloading) for r in results
                 if isinstance(r, SliceResult) and r.flight_unloading]
    if unloading:                     # a flighted drum's flights (flights.py)
        from .flights import plot_unloading, unloading_lines
        lines += unloading_lines(unloading) + ["![flight unloading](flights.png)"]
        plot_unloading(unloading, out_dir / "flights.png")
    md.write_text("\n".join(lines) + "\n")
    js = out_dir / "map.json"
    extra = {"flight_unloading": [{"holdup_kg_per_m": h, "incline_deg": i, **p}
                                  for h, i, p in unloading]} if unloading else {}
    js.write_text(json.dumps({"scene": scene_name, "units": {n: _unit(n) for n in figures},
                              "machine": machine or {}, "rows": rows, **extra}, indent=1,
                             default=float))
    png = out_dir / "map.png"
    _plot(rows, png)
    return [csv, md, js, png]


def _unit(name: str) -> str:
    if name in FIGURES:
        return FIGURES[name]
    return BODY_FIGURES.get(name.split("/")[-1], "")


def _cell(value) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.8g}"
    return str(value)


def _plot(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    holdup = [r["holdup_kg_per_m"] for r in rows]
    torques = sorted({k for r in rows for k in r if k.endswith("/torque_per_metre")})
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for name in torques:
        axes[0].errorbar(holdup, [r.get(name, np.nan) for r in rows],
                         yerr=[r.get(name + "_standard_error", 0.0) for r in rows],
                         marker="o", capsize=3, label=name.split("/")[0])
    axes[0].set_xlabel("hold-up (kg/m)")
    axes[0].set_ylabel("axial torque per metre (N m/m)")
    if torques:
        axes[0].legend()
    axes[1].errorbar(holdup, [r.get("axial_mass_flow", np.nan) for r in rows],
                     yerr=[r.get("axial_mass_flow_standard_error", 0.0) for r in rows],
                     marker="o", capsize=3)
    axes[1].set_xlabel("hold-up (kg/m)")
    axes[1].set_ylabel("axial mass flow (kg/s)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def add_arguments(p) -> None:
    """The ``taichi-dem map`` arguments."""
    p.add_argument("scene", help="a periodic slice scene (one periodic axis along the bodies' "
                                 "axis, a particle fill, no factories or outlets)")
    p.add_argument("--holdup", nargs="+", required=True,
                   help="hold-ups: kg/m ('60 kg/m', or a bare number) or a fill fraction of the "
                        "free section ('25 %%')")
    p.add_argument("--time", type=float, required=True,
                   help="simulated seconds per hold-up (the steady state is detected in them)")
    p.add_argument("--incline", type=float, nargs="+", default=None,
                   help="inclines (deg, the +axis end raised; gravity keeps its magnitude): the "
                        "map at each; two or more let the march tell what the machine conveys "
                        "by itself from what the slope adds (default: the scene's gravity)")
    p.add_argument("--fill", type=int, default=0, help="the [[particles]] fill whose count is set")
    p.add_argument("--out", default=None, help="folder for map.csv, map.md, map.json, map.png "
                                               "(default: <scene>_map beside the scene)")
    p.add_argument("--add", action="store_true",
                   help="add these slices to the map already in --out (the same scene and "
                        "--set): a hold-up and incline mapped again replaces its row; the "
                        "table, JSON and plot are written again from all rows")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a scene key changed for every slice (one value; repeatable), e.g. "
                        "simulation.precision=f64 or particles.0.radius=0.012: the map of a "
                        "modelling choice, to set beside the scene's own")
    p.add_argument("--stagger", type=float, default=None, metavar="DEG",
                   help="paddle rows turned DEG each from the one before: the slice (one row) "
                        "is made the repeating unit of rows (45 deg with 4 paddles: 2 rows, "
                        "30: 3; app/stagger.py); default: the scene's own rows")
    p.add_argument("--arch", default="cpu", choices=["cpu", "gpu", "cuda", "vulkan", "metal"],
                   help="where the kernels run: cpu, or a GPU backend (gpu picks one; default cpu)")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="CPU threads per slice (default: all cores); 1 for maps run side by "
                        "side, or with --dask workers")
    p.add_argument("--pictures", action="store_true",
                   help="a picture of each slice's bed at the end of its run: "
                        "OUT/bed_<hold-up>kgm_<incline>deg.png, the cross-section along the axis "
                        "coloured by axial speed")
    p.add_argument("--dask", action="store_true",
                   help="run the slices as tasks on Dask workers (a LocalCluster here, or "
                        "--scheduler) instead of one after another in this process")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", default=None,
                   help="an existing Dask scheduler (implies --dask; the workers need this "
                        "taichi-dem and the scene's files)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="LocalCluster workers for --dask (default: the cores)")


def _print_result(result: SliceResult) -> None:
    torque = {k: v for k, v in result.figures.items() if k.endswith("/torque_per_metre")}
    print(f"incline {result.incline:.3g} deg, hold-up {result.holdup:.4g} kg/m "
          f"({result.particles} particles): axial mass flow "
          f"{result.figures.get('axial_mass_flow', 'n/a')} kg/s, "
          + ", ".join(f"{k.split('/')[0]} torque {v} N m/m" for k, v in torque.items()),
          flush=True)


def _rows_to_add_to(out: Path, scene_name: str, info: dict) -> list[dict]:
    """The rows of the map in ``out`` that ``--add`` adds to, refused (file: key: reason)
    unless it is this scene's with the same changes and machine."""
    js = out / "map.json"
    try:
        doc = json.loads(js.read_text())
    except OSError as err:
        raise SceneError(str(js), "", f"--add: cannot read the map to add to: "
                         f"{err.strerror}") from None
    except json.JSONDecodeError as err:
        raise SceneError(str(js), "", f"--add: not a map (JSON): {err}") from None
    if doc.get("scene") != scene_name:
        raise SceneError(str(js), "scene", f"--add: the map is of {doc.get('scene')!r}, not "
                         f"{scene_name!r}")
    theirs = doc.get("machine", {})
    for key in ("scene_changes", "particle_diameter", "shell_radius", "period", "axis",
                "stagger_deg"):
        a, b = theirs.get(key), info.get(key)
        same = (a == b if not isinstance(a, float) or not isinstance(b, float)
                else math.isclose(a, b, rel_tol=1e-9))
        if not same:
            raise SceneError(str(js), f"machine.{key}", f"--add: the map has {a!r}, these "
                             f"slices {b!r}: not the same slice")
    return list(doc.get("rows", []))


def _picture(args, out: Path, holdup, incline) -> str | None:
    """Where --pictures puts the bed of the slice at ``holdup`` (parse_holdup's) and
    ``incline`` (deg, None: the scene's)."""
    if not getattr(args, "pictures", False):
        return None
    kind, value = holdup
    h = f"{value:g}kgm" if kind == "kg/m" else f"{100 * value:g}pct"
    tilt = "scene" if incline is None else f"{incline:g}deg"
    return str(out / f"bed_{h}_{tilt}.png")


def cmd_map(args) -> int:
    """``taichi-dem map``: the slice at each hold-up, its steady figures, the table and plot."""
    import sys
    path = Path(args.scene)
    try:
        text = path.read_text()
    except OSError as err:
        raise SceneError(str(path), "", f"cannot read the scene: {err.strerror}") from None
    changes = {}
    if args.set:
        from .overrides import overridden_text, parse_set
        for arg in args.set:
            spec = parse_set(arg)
            if len(spec.values) != 1:
                raise SceneError("--set", spec.key, f"one value per key for a map, got "
                                 f"{len(spec.values)} (run one map per value)")
            changes[spec.key] = spec.values[0]
        text = overridden_text(text, changes, str(path))
    holdups = []
    for value in args.holdup:
        try:
            holdups.append(parse_holdup(value))
        except ValueError as err:
            raise SceneError("--holdup", "", str(err)) from None
    if args.threads is not None and args.threads < 1:
        raise SceneError("--threads", "", f"must be at least 1, got {args.threads}")
    if not args.time > 0.0:
        raise SceneError("--time", "", f"must be > 0 s, got {args.time}")
    from ..scene.loader import parse_scene
    scene = parse_scene(text, source=str(path), base_dir=path.parent)
    geometry = slice_geometry(scene)
    stagger_rows = None
    if getattr(args, "stagger", None) is not None:
        # the repeating unit of rows turned by the stagger (app/stagger.py)
        from .overrides import to_text
        from .stagger import staggered_doc
        doc, stagger_rows = staggered_doc(tomllib.loads(text), args.stagger, str(path),
                                          geometry.axis, geometry.length)
        text = to_text(doc)
        scene = parse_scene(text, source=str(path), base_dir=path.parent)
        geometry = slice_geometry(scene)
        print(f"stagger {args.stagger:g} deg: a slice of {stagger_rows} row(s), "
              f"{geometry.length:.4g} m", file=sys.stderr)
    if not 0 <= args.fill < len(scene.fills):
        raise SceneError(str(path), "particles", f"--fill {args.fill}: the scene has "
                         f"{len(scene.fills)} fill(s)")
    scale = getattr(scene.settings.get("thermal"), "time_scale", 1.0) if scene.settings.get("thermal") is not None else 1.0
    if scale != 1.0:
        print(f"note: {path}: thermal.time_scale = {scale:g}: the conductance per metre is "
              "lowered where heat outruns the mixing (-71 % at 10 on a cooler slice); map "
              "the heat at 1 for the march's outlet temperature", file=sys.stderr)
    interval = scene.output.interval
    if interval and args.time < 4.0 * interval:
        raise SceneError("--time", "", f"{args.time:g} s holds fewer than 4 samples of "
                         f"output.interval = {interval:g} s: the steady means need more "
                         "(a map wants several seconds of steady flow)")
    for h in holdups:       # refuse every impossible hold-up before running any
        holdup_count(scene, geometry, h, args.fill)
    out = Path(args.out) if args.out else path.with_name(path.stem + "_map")
    info = machine_info(scene, geometry, args.fill)
    if changes:
        info["scene_changes"] = changes          # what --set changed: the modelling choice
    if stagger_rows is not None:
        info["stagger_deg"] = float(args.stagger)
        info["rows_per_slice"] = stagger_rows
    old_rows = _rows_to_add_to(out, path.name, info) if args.add else []
    jobs = [(i, h) for i in (args.incline or [None]) for h in holdups]
    if args.dask or args.scheduler:
        # one task per slice (sweep.make_client: a LocalCluster of processes, or a scheduler)
        from .sweep import close_client, make_client
        client = make_client(args.scheduler, args.workers)
        try:
            futures = [client.submit(run_slice, text, str(path), h, args.time, args.fill,
                                     base_dir=path.parent, arch=args.arch, incline=i,
                                     threads=args.threads, picture=_picture(args, out, h, i),
                                     pure=False)
                       for i, h in jobs]
            results = client.gather(futures)
        finally:
            close_client(client)
        for result in results:
            _print_result(result)
    else:
        results = []
        for incline, h in jobs:
            result = run_slice(text, str(path), h, args.time, args.fill, base_dir=path.parent,
                               arch=args.arch, incline=incline, threads=args.threads,
                               picture=_picture(args, out, h, incline))
            results.append(result)
            _print_result(result)
    new_keys = {(round(r.holdup, 6), round(r.incline, 6)) for r in results}
    kept = [r for r in old_rows
            if (round(r["holdup_kg_per_m"], 6), round(r["incline_deg"], 6)) not in new_keys]
    paths = write_map(kept + results, out, path.name, info)
    print("wrote " + ", ".join(str(p) for p in paths), file=sys.stderr)
    return 0
