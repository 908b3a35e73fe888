"""What a scene *is*: frozen, validated plain data in SI units (no Taichi).

The loader (:mod:`taichi_dem.scene.loader`) turns a TOML file into a :class:`Scene`; the engine
(:mod:`taichi_dem.run.simulation`) turns a Scene into device state. Nothing here allocates or
compiles anything, so a Scene can be built, inspected and validated cheaply (``taichi-dem check``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

Vec3 = tuple[float, float, float]


class AddedKeys:
    """A scene object whose section effects add keys to (scene/keys.py ``Section.adds``: a
    material's conductivity, a wall's temperature). Their values, SI or the key's default,
    are kept in ``effect_values`` and read as attributes (``wall.temperature``), so the
    scene's own code names none of them and a misspelt one is still an AttributeError."""

    def __getattr__(self, name: str):
        # (only called when the normal lookup fails; __dict__ read directly: no recursion
        # while a copy or an unpickled object is half made)
        values = self.__dict__.get("effect_values")
        if values is not None and name in values:
            return values[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


@dataclass(frozen=True)
class SimulationSettings(AddedKeys):
    end_time: float = 1.0                # s
    dt: Optional[float] = None           # s; None = automatic (rayleigh_fraction x Rayleigh time)
    rayleigh_fraction: float = 0.2
    precision: str = "f32"               # "f32" | "f64"
    seed: int = 1
    skin: Optional[float] = None         # m, Verlet skin; None = 0.1 x mean diameter (LAMMPS-like)
    # particle slots with factories; None = the initial particles plus what the factories'
    # schedules insert until end_time (10 % margin), at most what the domain can hold
    max_particles: Optional[int] = None
    # the keys effects add (scene/keys.py Section.adds: the gravity, m/s^2): {name: SI value,
    # or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class Domain:
    min: Vec3
    max: Vec3
    periodic: tuple[str, ...] = ()       # subset of ("x", "y", "z")


@dataclass(frozen=True)
class CalibrationTest:
    """One bench test of a calibration record: its target (the measured mean and scatter) and
    what the calibrated material achieved over ``runs`` fresh runs, in ``unit``."""
    name: str
    unit: str = ""
    scene: str = ""
    target: Optional[float] = None
    target_sd: Optional[float] = None
    achieved_mean: Optional[float] = None
    achieved_sd: Optional[float] = None
    achieved_sem: Optional[float] = None
    runs: int = 0
    within_scatter: Optional[bool] = None


@dataclass(frozen=True)
class CalibratedValue:
    """A calibrated parameter or choice: the spec's ``key``, its ``value`` and, when the record
    says so, the interaction ``pair`` and its ``field`` it sets."""
    key: str
    value: Any
    pair: Optional[tuple[str, str]] = None
    field: str = ""
    material: str = ""


@dataclass(frozen=True)
class Calibration:
    """[materials.NAME.calibration]: what the material was calibrated against (the record of
    ``taichi-dem calibrate``; ``source``: the file it was read from)."""
    source: str
    against: str = ""
    date: str = ""
    command: str = ""
    spec: str = ""
    sphere_radius: tuple[float, ...] = ()       # m: the sizes it holds for
    within_scatter: Optional[bool] = None
    tests: tuple[CalibrationTest, ...] = ()
    values: tuple[CalibratedValue, ...] = ()


@dataclass(frozen=True)
class Material(AddedKeys):
    name: str
    density: float                       # kg/m^3
    youngs_modulus: float                # Pa (possibly softened)
    poisson_ratio: float
    calibration: Optional[Calibration] = None      # what it was calibrated against
    # the keys effects add to a material (scene/keys.py Section.adds: the heat transfer's
    # conductivity and heat capacity, ...): {name: SI value, or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)

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
class ParticleFill(AddedKeys):
    """An initial fill: ``count`` spheres placed without overlap in ``region``, or the explicit
    particles of a CSV ``file`` (arrays already read, SI)."""
    key: str                             # e.g. "particles[0]", for error messages
    material: str
    radius: Optional[RadiusDistribution] = None
    count: int = 0
    region: Optional[Region] = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    angular_velocity: Vec3 = (0.0, 0.0, 0.0)
    fixed: bool = False
    file: Optional[str] = None
    positions: Optional[np.ndarray] = None          # (n,3) from file
    radii: Optional[np.ndarray] = None              # (n,)
    velocities: Optional[np.ndarray] = None         # (n,3) or None
    angular_velocities: Optional[np.ndarray] = None # (n,3) or None
    frame: Optional[int] = None                     # the results file's frame a fill starts from
    # the per-particle fields effects add to a results file's frame, as the fill's frame
    # gives them (catalog.frame_fields: {name: (n,) array})
    frame_values: dict = field(default_factory=dict, compare=False)
    # the keys effects add (scene/keys.py Section.adds: a temperature, ...): {name: SI value,
    # or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)

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
class PlaneWall(AddedKeys):
    """An analytic infinite plane; particles live on the side ``normal`` points to."""
    name: str
    point: Vec3
    normal: Vec3                         # unit
    material: str
    # the keys effects add (scene/keys.py Section.adds: a temperature, ...): {name: SI value,
    # or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class Output:
    interval: float = 0.05               # s
    frame_interval: Optional[float] = None   # s between particle frames; None: every sample
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
class Factory(AddedKeys):
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
    interval: Optional[float] = None     # s between insertions; None = automatic
    pattern: str = "random"              # "random" (in region) | "sheet" (layers through a face)
    sheet: Optional[SheetInlet] = None   # the face, for pattern "sheet"
    # the keys effects add (scene/keys.py Section.adds: a temperature, ...): {name: SI value,
    # or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)

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
    factories: tuple[Factory, ...] = ()
    outlets: tuple[Outlet, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    # the settings of every effect section the scene has (or another section implies), by
    # section name: what an effect's settings module returns for it (scene/keys.py
    # ``Section.reader``, ``Section.derive``): settings["gas"] is the drag's (DragSettings);
    # a section the scene does not enable is absent
    settings: dict = field(default_factory=dict)

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
class Body(AddedKeys):
    """A rigid triangle-mesh body (one or several meshes), its material and motion."""
    key: str                             # "bodies[0]"
    name: str
    material: str
    vertices: np.ndarray                 # (V, 3) m, all meshes merged, at t = 0
    faces: np.ndarray                    # (F, 3) int
    motion: Motion = field(default_factory=Motion)
    # the keys effects add (scene/keys.py Section.adds: a temperature, ...): {name: SI value,
    # or the key's default}
    effect_values: dict = field(default_factory=dict, compare=False)
