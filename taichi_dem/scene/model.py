"""What a scene *is*: frozen, validated plain data in SI units (no Taichi).

The loader (:mod:`taichi_dem.scene.loader`) turns a TOML file into a :class:`Scene`; the engine
(:mod:`taichi_dem.run.simulation`) turns a Scene into device state. Nothing here allocates or
compiles anything, so a Scene can be built, inspected and validated cheaply (``taichi-dem check``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class SimulationSettings:
    end_time: float = 1.0                # s
    dt: Optional[float] = None           # s; None = automatic (rayleigh_fraction x Rayleigh time)
    rayleigh_fraction: float = 0.2
    gravity: Vec3 = (0.0, 0.0, -9.81)    # m/s^2
    precision: str = "f32"               # "f32" | "f64"
    seed: int = 1
    skin: Optional[float] = None         # m, Verlet skin; None = 0.1 x mean diameter (LAMMPS-like)
    # particle slots with factories; None = the initial particles plus what the factories'
    # schedules insert until end_time (10 % margin), at most what the domain can hold
    max_particles: Optional[int] = None


@dataclass(frozen=True)
class Domain:
    min: Vec3
    max: Vec3
    periodic: tuple[str, ...] = ()       # subset of ("x", "y", "z")


@dataclass(frozen=True)
class CoarseGraining:
    """[materials.NAME] coarse_grained: the particles stand for a bed of finer ones, and take
    heat from walls and bodies as that bed would (thermal/coarse_grained.py)."""
    represented_diameter: float          # m, the real particles' diameter
    bed_porosity: float = 0.4            # of the real bed: its bulk density and conductivity
    surface_coverage: float = 0.8        # Schlünder's phi_A, the wall's coverage by the first layer
    roughness: float = 0.0               # m, Schlünder's delta, added to the mean free path


@dataclass(frozen=True)
class Material:
    name: str
    density: float                       # kg/m^3
    youngs_modulus: float                # Pa (possibly softened)
    poisson_ratio: float
    thermal_conductivity: Optional[float] = None   # W/(m K)
    heat_capacity: Optional[float] = None          # J/(kg K)
    emissivity: Optional[float] = None
    real_youngs_modulus: Optional[float] = None    # Pa, unsoftened (conduction correction)
    coarse_grained: Optional[CoarseGraining] = None  # heat to walls as the represented bed

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + v)), Pa."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))


@dataclass(frozen=True)
class Interaction:
    pair: tuple[str, str]
    restitution: float                   # (0, 1]
    friction: float                      # Coulomb sliding coefficient mu_s >= 0
    rolling_friction: float = 0.0        # mu_r >= 0; 0 disables
    rolling_model: str = "constant_torque"   # "constant_torque" | "epsd"
    rolling_damping: float = 0.3         # EPSD viscous part, fraction of critical (Ai et al. 2011)


@dataclass(frozen=True)
class RadiusDistribution:
    """Constant radius (std = 0) or a normal distribution truncated to [min, max], m."""
    mean: float
    std: float = 0.0
    min: Optional[float] = None
    max: Optional[float] = None

    @property
    def largest(self) -> float:
        return self.mean if self.std == 0.0 else float(self.max)

    @property
    def smallest(self) -> float:
        return self.mean if self.std == 0.0 else float(self.min)


@dataclass(frozen=True)
class Region:
    """A box (``box_min``/``box_max``) or a cylinder running from ``axis_point`` along the unit
    ``axis_direction`` for ``length`` with ``radius``."""
    kind: str                            # "box" | "cylinder"
    box_min: Optional[Vec3] = None
    box_max: Optional[Vec3] = None
    axis_point: Optional[Vec3] = None
    axis_direction: Optional[Vec3] = None
    radius: Optional[float] = None
    length: Optional[float] = None


@dataclass(frozen=True, eq=False)
class ParticleFill:
    """An initial fill: ``count`` spheres placed without overlap in ``region``, or the explicit
    particles of a CSV ``file`` (arrays already read, SI)."""
    key: str                             # e.g. "particles[0]", for error messages
    material: str
    radius: Optional[RadiusDistribution] = None
    count: int = 0
    region: Optional[Region] = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    angular_velocity: Vec3 = (0.0, 0.0, 0.0)
    temperature: Optional[float] = None
    moisture: Optional[float] = None     # kg water per kg dry solid; None = dry (no drying)
    fixed: bool = False
    file: Optional[str] = None
    positions: Optional[np.ndarray] = None          # (n,3) from file
    radii: Optional[np.ndarray] = None              # (n,)
    velocities: Optional[np.ndarray] = None         # (n,3) or None
    angular_velocities: Optional[np.ndarray] = None # (n,3) or None

    @property
    def largest_radius(self) -> float:
        if self.radii is not None:
            return float(np.max(self.radii)) if len(self.radii) else 0.0
        return self.radius.largest

    @property
    def smallest_radius(self) -> float:
        if self.radii is not None:
            return float(np.min(self.radii)) if len(self.radii) else np.inf
        return self.radius.smallest

    @property
    def expected_count(self) -> int:
        return len(self.radii) if self.radii is not None else self.count


@dataclass(frozen=True)
class PlaneWall:
    """An analytic infinite plane; particles live on the side ``normal`` points to."""
    name: str
    point: Vec3
    normal: Vec3                         # unit
    material: str
    temperature: Optional[float] = None  # K; None = adiabatic


@dataclass(frozen=True)
class DragSettings:
    """Drag from a gas on the particles (effects/drag.py), one-way coupled: ``model``
    "di_felice" (local voidage from the cell grid) or "schiller_naumann" (dilute); the gas's
    superficial ``velocity`` m/s (uniform), ``density`` kg/m^3 and ``viscosity`` Pa s. From
    the mechanics-only [gas] section or from [thermal.gas] with ``drag``."""
    model: str
    velocity: Vec3
    density: float
    viscosity: float


@dataclass(frozen=True)
class GasSettings:
    """The gas particles exchange heat with by convection (air at 300 K by default).

    ``"fixed"``: uniform ``temperature`` and ``velocity``. ``"axial_plug_flow"``: a 1-D stream
    along the axis from ``axis_point`` along unit ``axis_direction`` for ``length``, in
    ``cells`` equal cells, entering at the axis_point end (``flow = "along_axis"``) or at the
    far end (``"against_axis"``) with ``mass_flow`` kg/s at ``temperature`` (the inlet
    temperature, K); ``velocity`` is then the stream's, mass_flow / (density flow_area) along
    the flow (the loader derives it)."""
    model: str = "fixed"                 # "fixed" | "axial_plug_flow"
    temperature: float = 300.0           # K (plug flow: the inlet temperature)
    velocity: Vec3 = (0.0, 0.0, 0.0)     # m/s
    correlation: str = "ranz_marshall"   # Nusselt correlation: "ranz_marshall" | "gunn"
    porosity: float = 0.4                # bed voidage for "gunn"
    density: float = 1.177               # kg/m^3
    viscosity: float = 1.846e-5          # Pa s
    conductivity: float = 0.02624        # W/(m K)
    heat_capacity: float = 1007.0        # J/(kg K)
    # axial_plug_flow only
    axis_point: Vec3 = (0.0, 0.0, 0.0)   # m
    axis_direction: Vec3 = (1.0, 0.0, 0.0)   # unit
    length: float = 0.0                  # m
    cells: int = 0
    flow_area: float = 0.0               # m^2, the gas's free cross-section
    mass_flow: float = 0.0               # kg/s
    flow: str = "along_axis"             # "along_axis" | "against_axis"
    drag: str = "none"                   # "none" | "di_felice" | "schiller_naumann"

    @property
    def plug_flow(self) -> bool:
        return self.model == "axial_plug_flow"


@dataclass(frozen=True)
class ThermalSettings:
    """[thermal]: present = heat transfer compiled and run; each part switchable."""
    conduction: bool = True              # particle-particle, through the contact area
    wall_conduction: bool = True         # to walls and bodies that have a temperature
    radiation: bool = False              # grey-body exchange with ``radiation_to``
    gas: Optional[GasSettings] = None    # None = no convection
    # correction of the contact radius for softened stiffness: "static" a ~ E*^(-1/3)
    # (enduring contacts, the default), "collision" a ~ E*^(-1/5) (Morris et al. 2016), "none"
    contact_radius_correction: str = "static"
    # radiation: what the particles see - "gas" (the local gas temperature), "surface" (the
    # wall/body radiation_surface) or "enclosure" (at radiation_temperature); only inside
    # radiation_region if given
    radiation_to: str = ""
    radiation_surface: Optional[str] = None          # wall/body name when "surface"
    radiation_temperature: Optional[float] = None    # K, for "surface" and "enclosure"
    radiation_region: Optional[Region] = None
    # moisture: on when any fill (or factory) gives ``moisture``
    moisture: bool = False
    evaporation_temperature: float = 373.15          # K
    latent_heat: float = 2.26e6                      # J/kg
    water_heat_capacity: float = 4186.0              # J/(kg K), liquid water
    # conduction through the gas gap near particle-particle (with conduction on; unless
    # gas_gap_pairs is false) and particle-wall/body contacts (thermal/gas_gap.py): the fluid
    # lens gas_gap_lens radii thick, gaps narrower than gas_gap_min_gap m count as it (MFiX's
    # defaults: lens 0.2 R; a minimum gap of about 1 um, the roughness scale)
    gas_gap: bool = False
    gas_gap_pairs: bool = True
    # "solid_resistance": the particle's own resistance in series with the gas along each
    # line (Cheng, Yu & Zulli 1999); "isothermal": isothermal surfaces (Rong & Horio 1999,
    # Musser 2011, Morris et al. 2015), an upper bound where k_g/k_s is not small
    # "voronoi": the solid's resistance from the Voronoi cones, not the centre planes (Cheng,
    # Yu & Zulli 1999), with the packing's porosity gas_gap_porosity setting the cones
    gas_gap_model: str = "solid_resistance"
    gas_gap_porosity: float = 0.4
    # thermal time scaling: every heat capacity divided by time_scale S, so temperatures move
    # S times faster than the mechanics; thermal time = S x simulated time (series
    # thermal_time); heat flows (W) stay physical
    time_scale: float = 1.0
    gap_gas_conductivity: float = 0.02624            # W/(m K); air at 300 K
    gas_gap_lens: float = 0.2                        # of the particle radius
    gas_gap_min_gap: float = 1.0e-6                  # m


@dataclass(frozen=True)
class MobilitySettings:
    """[mobility]: skip the contacts and the integration of particles that do not move
    (effects/mobility.py). Cells of the mobility grid (blocks of contact cells about
    ``cell_size`` across) are judged at every neighbour rebuild: *mobile* when the granular
    temperature of their particles (velocity fluctuation about the cell mean, (m/s)^2) or the
    squared mean velocity exceeds ``granular_temperature_threshold``, when their solid
    fraction is below ``solid_fraction_threshold``, when the rms acceleration of their
    particles exceeds ``acceleration_threshold`` (a bed still ringing after an impact is not
    in equilibrium: freezing it would freeze its forces) or when they touch an empty cell; *active*
    within one cell of a mobile one; *inactive* otherwise. Velocities are taken relative to
    the rigid motion of ``body`` in mode "body_frame" (drums, coolers), to rest in mode
    "at_rest"."""
    granular_temperature_threshold: float    # (m/s)^2 (resolved: "auto" = 1e-5 g d_max)
    solid_fraction_threshold: float = 0.4
    cell_size: float = 0.0                   # m (resolved: "auto" = 3 d_max)
    mode: str = "at_rest"                    # "at_rest" | "body_frame"
    acceleration_threshold: float = math.inf  # m/s^2, rms acceleration; inf = not checked
    body: Optional[str] = None               # the body whose frame "body_frame" uses
    threshold_is_auto: bool = False


@dataclass(frozen=True)
class Output:
    interval: float = 0.05               # s
    rrd: Optional[str] = None
    h5: Optional[str] = None
    checkpoint_interval: Optional[float] = None


@dataclass(frozen=True)
class RateSchedule:
    """Piecewise-constant mass rate: ``points`` = ((start time s, rate kg/s), ...), sorted by
    time; the first starts at 0."""
    points: tuple[tuple[float, float], ...]

    def at(self, time: float) -> float:
        """Mass rate at ``time``, kg/s."""
        rate = self.points[0][1]
        for start, value in self.points:
            if time >= start:
                rate = value
        return rate

    def mass_until(self, time: float) -> float:
        """Mass scheduled from t = 0 to ``time``, kg (the integral of the rate)."""
        total = 0.0
        for k, (start, rate) in enumerate(self.points):
            if time <= start:
                break
            end = self.points[k + 1][0] if k + 1 < len(self.points) else math.inf
            total += rate * (min(time, end) - start)
        return total

    def time_for_mass(self, mass: float) -> float:
        """The earliest time (s) at which ``mass_until`` reaches ``mass`` (kg); inf if never."""
        if mass <= 0.0:
            return 0.0
        total = 0.0
        for k, (start, rate) in enumerate(self.points):
            end = self.points[k + 1][0] if k + 1 < len(self.points) else math.inf
            seg = rate * (end - start) if rate > 0.0 else 0.0
            if rate > 0.0 and total + seg >= mass:
                return start + (mass - total) / rate
            total += seg
        return math.inf

    @property
    def max_rate(self) -> float:
        """The largest scheduled rate, kg/s."""
        return max(r for _, r in self.points)


@dataclass(frozen=True)
class SheetInlet:
    """The face of a ``pattern = "sheet"`` factory: the rectangle ``point + a width + b depth``
    (0 <= a, b <= 1; ``width`` and ``depth`` perpendicular edge vectors, m) that the stream
    crosses along the unit ``normal`` (the side the factory's velocity points to).

    Each layer is a square lattice of pitch ``pitch`` in the face, every other layer shifted by
    half a pitch along both edges (the hollows of the one before), the centres ``radius +
    jitter_amplitude`` in front of the face and half a pitch from its edges (so a face that
    spans a periodic axis keeps its spheres clear across it too), each displaced at random by at
    most ``jitter_amplitude`` (= ``jitter`` x diameter). The pitch is the contact distance plus
    twice the jitter (and a 1e-3 clearance), so no two spheres of one layer can touch; two
    successive layers are then clear of each other while their spacing along the normal is at
    least ``min_layer_spacing`` = sqrt(pitch^2 - pitch^2/2) = pitch / sqrt(2) (the shifted
    neighbour lies pitch/sqrt(2) away in the face). The spacing itself follows from the
    requested mass rate: a layer of mass M is due when the stream has carried the previous
    one M u_n / mass_rate further (see process/factories.py), so the inflow's bulk density is
    mass_rate / (u_n |width| |depth|) whatever the lattice."""
    point: Vec3                          # m, a corner of the face
    width: Vec3                          # m, edge vector
    depth: Vec3                          # m, edge vector, perpendicular to width
    normal: Vec3                         # unit, along the stream
    radius: float                        # m, the one particle radius
    jitter: float = 0.05                 # fraction of the diameter (largest displacement)

    @property
    def jitter_amplitude(self) -> float:
        """Largest displacement of a centre from its lattice site, m."""
        return self.jitter * 2.0 * self.radius

    @property
    def pitch(self) -> float:
        """Lattice pitch in the face, m."""
        return 2.0 * self.radius * (1.0 + 1e-3) + 2.0 * self.jitter_amplitude

    @property
    def min_layer_spacing(self) -> float:
        """Closest two successive (mutually shifted) layers may be along the normal, m."""
        return self.pitch / math.sqrt(2.0)

    @property
    def extents(self) -> tuple[float, float]:
        """|width|, |depth| (m)."""
        return float(np.linalg.norm(self.width)), float(np.linalg.norm(self.depth))

    def sites(self, parity: int) -> np.ndarray:
        """(n, 2) lattice sites of a layer of ``parity`` 0 or 1 as (a, b) distances (m) along the
        width and depth edges from ``point``."""
        margin = 0.5 * self.pitch
        axes = []
        for extent in self.extents:
            span = extent - 2.0 * margin - 0.5 * self.pitch * parity
            if span < 0.0:
                return np.empty((0, 2))
            n = int(math.floor(span / self.pitch + 1e-9)) + 1
            axes.append(margin + 0.5 * self.pitch * parity + self.pitch * np.arange(n))
        a, b = np.meshgrid(axes[0], axes[1], indexing="ij")
        return np.stack([a.ravel(), b.ravel()], axis=1)

    def layer_counts(self) -> tuple[int, int]:
        """Spheres in a layer of parity 0 and 1."""
        return len(self.sites(0)), len(self.sites(1))

    def max_mass_rate(self, density: float, speed: float) -> float:
        """The largest mass rate (kg/s) the lattice can carry at normal speed ``speed`` (m/s):
        two successive layers (one of each parity) per 2 x min_layer_spacing."""
        n0, n1 = self.layer_counts()
        m = 4.0 / 3.0 * math.pi * self.radius ** 3 * density
        return 0.5 * (n0 + n1) * m * speed / self.min_layer_spacing


@dataclass(frozen=True, eq=False)
class Factory:
    """Continuous insertion at a scheduled mass rate into ``region`` without overlap
    (``pattern = "random"``), or as lattice layers through the face ``sheet`` (``"sheet"``).

    Radii: a truncated normal (``radius``) sampled by number, or ``sizes`` = ((radius m, mass
    fraction), ...) sampled so each size gets its fraction of the inserted mass."""
    key: str                             # "factories[0]"
    name: str
    material: str
    region: Optional[Region]             # None for pattern "sheet"
    mass_rate: RateSchedule
    radius: Optional[RadiusDistribution] = None
    sizes: Optional[tuple[tuple[float, float], ...]] = None
    velocity: Vec3 = (0.0, 0.0, 0.0)     # m/s
    temperature: Optional[float] = None  # K
    moisture: Optional[float] = None     # kg water per kg dry solid; None = dry
    interval: Optional[float] = None     # s between insertions; None = automatic
    pattern: str = "random"              # "random" (in region) | "sheet" (layers through a face)
    sheet: Optional[SheetInlet] = None   # the face, for pattern "sheet"

    @property
    def largest_radius(self) -> float:
        return max(r for r, _ in self.sizes) if self.sizes else self.radius.largest

    @property
    def smallest_radius(self) -> float:
        return min(r for r, _ in self.sizes) if self.sizes else self.radius.smallest

    def mean_particle_volume(self) -> float:
        """Expected volume of one inserted particle, m^3."""
        if self.sizes:
            # number fraction of size k ~ mass fraction / r^3
            n = [f / r ** 3 for r, f in self.sizes]
            return sum(nk * 4.0 / 3.0 * math.pi * r ** 3 for nk, (r, _) in zip(n, self.sizes)) / sum(n)
        d = self.radius
        if d.std == 0.0:
            return 4.0 / 3.0 * math.pi * d.mean ** 3
        return 4.0 / 3.0 * math.pi * (d.mean ** 3 + 3.0 * d.mean * d.std ** 2)


@dataclass(frozen=True)
class Outlet:
    """Particles whose centre enters ``region`` are removed and accounted."""
    key: str
    name: str
    region: Region


@dataclass(frozen=True)
class Sensor:
    """An observer: ``mass_flow`` through a plane (optionally within a disk ``radius`` about
    ``point`` or a ``box``), ``residence_time`` from factory ``source`` to outlet ``target``,
    or ``contact_count`` of particles touching ``body``."""
    key: str
    name: str
    kind: str                            # "mass_flow" | "residence_time" | "contact_count"
    point: Optional[Vec3] = None
    normal: Optional[Vec3] = None        # unit
    radius: Optional[float] = None       # m, disk bound of a mass_flow plane
    box_min: Optional[Vec3] = None       # m, box bound of a mass_flow plane
    box_max: Optional[Vec3] = None
    source: Optional[str] = None         # factory name (residence_time "from")
    target: Optional[str] = None         # outlet name (residence_time "to")
    body: Optional[str] = None           # contact_count


@dataclass(frozen=True, eq=False)
class Scene:
    source: str                          # file path (or "<string>") for messages
    text: str                            # the TOML text, stored in results
    simulation: SimulationSettings
    domain: Domain
    materials: dict[str, Material]
    interactions: dict[frozenset, Interaction]
    fills: tuple[ParticleFill, ...] = ()
    walls: tuple[PlaneWall, ...] = ()
    bodies: tuple["Body", ...] = ()
    output: Output = field(default_factory=Output)
    thermal: Optional[ThermalSettings] = None
    factories: tuple[Factory, ...] = ()
    outlets: tuple[Outlet, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    drag: Optional[DragSettings] = None
    mobility: Optional[MobilitySettings] = None

    def interaction(self, a: str, b: str) -> Interaction:
        return self.interactions[frozenset((a, b))]

    @property
    def expected_particle_count(self) -> int:
        return sum(f.expected_count for f in self.fills)


@dataclass(frozen=True)
class SpeedSchedule:
    """Piecewise-constant angular speed: ``points`` = ((start time s, speed rad/s), ...),
    sorted by time; the first starts at 0."""
    points: tuple[tuple[float, float], ...]

    def at(self, time: float) -> float:
        """Angular speed at ``time``, rad/s."""
        speed = self.points[0][1]
        for start, value in self.points:
            if time >= start:
                speed = value
        return speed


@dataclass(frozen=True)
class Motion:
    """Prescribed rigid motion: rotation about an axis (speed schedule, rad/s, right-handed
    about ``axis_direction``) and/or translation at constant ``velocity`` (m/s)."""
    axis_point: Vec3 = (0.0, 0.0, 0.0)
    axis_direction: Vec3 = (1.0, 0.0, 0.0)          # unit
    speed: Optional[SpeedSchedule] = None            # None: no rotation
    velocity: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, eq=False)
class Body:
    """A rigid triangle-mesh body (one or several meshes), its material and motion."""
    key: str                             # "bodies[0]"
    name: str
    material: str
    vertices: np.ndarray                 # (V, 3) m, all meshes merged, at t = 0
    faces: np.ndarray                    # (F, 3) int
    motion: Motion = field(default_factory=Motion)
    temperature: Optional[float] = None  # K; None = adiabatic
