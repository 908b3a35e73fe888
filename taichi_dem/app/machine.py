"""The whole machine from its map (issue 31 item 2): march along the axis from the discharge,
at each position the hold-up that carries the feed, as Kramers & Croockewit (1952) and Saeman
(1951) do for rotary drums.

The map (app/slice_map.py) gives, for periodic slices at hold-ups H (kg/m) and at one or more
inclines, the steady axial mass flow q (kg/s, along the slice's +axis), the dynamic angle beta,
and per body the torque, drive power and shell conductance per metre. A slice has no axial
gradient; in a machine the bed's depth h changes along the axis, and the slope of its free
surface drives the surface layer as an incline would. Kramers' bed-depth equation for a drum,

    dh/dx = tan(beta) [ 3 Phi_v / (4 pi n R^3) (2h/R - h^2/R^2)^(-3/2) - tan(theta) / sin(beta) ]

(x from the discharge towards the feed, Phi_v m^3/s, n rev/s, R the drum radius, theta the
incline), is the statement that the flow is Saeman's uniform-bed flow at an *effective* slope

    s = tan(theta) + cos(beta) dh/dx,        q = rho_b (4/3) pi n (c/2)^3 s / sin(beta)

(c the chord of the bed surface, rho_b the bulk density). The march generalises exactly this:
the map's flow at each hold-up is fitted as q(H, s) = a(H) + b(H) s over the inclines mapped
(a: what the machine conveys by itself - paddles, flights, screws; b: what the slope adds; a
plain drum has a = 0 and one incline suffices), and at each position the depth gradient is the
one at which q equals the feed. For a plain drum it reduces to Kramers' equation (tested).

The depth gradient drives the bed, not what is in flight. An incline tilts gravity for every
particle, but a bed's free surface sloping along the axis pushes only the particles resting in
it: the curtains of a flighted drum fall the same whatever the bed's depth below. Where the map
has airborne_mass_flow (the part of q carried in flight, app/curtains.py), the gradient acts
through the rest only:

    q = a + b tan(theta) + phi_bed b cos(beta) dh/dx,      phi_bed = 1 - q_airborne / q

(the mean over the inclines at each hold-up: the bed's share of the flow stands for its share
of the slope's effect, exact for a map at one incline, q = b s). In the flighted drums mapped
the curtains carry 41 - 79 % of the flow (docs/machine/dryer_slice/), so the bed needs 1.7 -
5x the gradient to carry the same excess, and the hold-up falls over a shorter stretch before
a free discharge. A map without the figure (a plain drum, a map written before it) keeps
phi_bed = 1. The error draws (with_errors) draw the airborne flow independently of the whole,
which overstates the spread phi_bed adds a little.

Along the marched profile H(x): the hold-up M = int H dx (kg), the mean residence time
tau = M / F (the plug-flow mean: hold-up over throughput, exact for any mixing at steady state),
each body's torque and power int T(H) dx, and the outlet temperature of a bed cooled (or heated)
through the shell at the map's conductance per metre U(H) (W/(m K)):
T_out = T_w + (T_in - T_w) exp(-int U dx / (F c_p)). The conductance is a ratio of real heat
flow to the bed's mean temperature difference, and the residence here is real time. Map the
slice without a thermal time scale: with [thermal] time_scale = S the bed's heat moves S times
faster than its mixing (likely: the particles at the wall drained before the mixing renews
them), and the conductance falls (measured on bench/direct_check/cooler_slice.toml at S = 10: -71 %,
BENCHMARKS.md "Stop 25"); the march's outlet temperature assumes it was mapped at S = 1.

The capacity is the largest feed whose profile stays below the overflow hold-up everywhere
(by default the largest mapped hold-up: the march does not extrapolate beyond the map).
Each figure's error is the standard deviation over re-marches with the map's figures drawn
from their steady means and standard errors (independent normal draws per row).
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SceneError


# ---- the cross-section -------------------------------------------------------------------

def _segment(radius: float, depth):
    """Area (m^2) of a circle of ``radius`` below a level ``depth`` above its lowest point."""
    d = np.clip(depth, 0.0, 2.0 * radius)
    return radius ** 2 * np.arccos((radius - d) / radius) - (radius - d) * np.sqrt(
        np.maximum(2.0 * radius * d - d * d, 0.0))


@dataclass(frozen=True)
class Section:
    """The free cross-section of the machine: a shell of ``shell_radius`` (m) around a coaxial
    shaft of ``shaft_radius`` (m, 0 for a drum), filled with a bed of ``bulk_density``
    (kg/m^3). Depths h are measured from the shell's lowest point up (m)."""
    shell_radius: float
    shaft_radius: float
    bulk_density: float

    def area(self, depth):
        """The bed's cross-section (m^2) at depth ``depth`` (m): the shell's segment less the
        part of the shaft below the level."""
        R, r = self.shell_radius, self.shaft_radius
        shaft = _segment(r, np.asarray(depth, float) - (R - r)) if r > 0.0 else 0.0
        return _segment(R, depth) - shaft

    def holdup(self, depth):
        """Hold-up (kg/m) at bed depth ``depth`` (m)."""
        return self.bulk_density * self.area(depth)

    def chord(self, depth):
        """Width (m) of the bed's free surface across the shell at ``depth`` (the shaft, when
        the level crosses it, does not change Saeman's chord: the surface layer flows around)."""
        R = self.shell_radius
        d = np.clip(np.asarray(depth, float), 0.0, 2.0 * R)
        return 2.0 * np.sqrt(np.maximum(2.0 * R * d - d * d, 0.0))

    def depth(self, holdup) -> np.ndarray:
        """Bed depth (m) that holds ``holdup`` (kg/m), by bisection (the area grows with depth)."""
        H = np.atleast_1d(np.asarray(holdup, float))
        lo, hi = np.zeros_like(H), np.full_like(H, 2.0 * self.shell_radius)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            low = self.holdup(mid) < H
            lo, hi = np.where(low, mid, lo), np.where(low, hi, mid)
        return 0.5 * (lo + hi)


def saeman_flow(section: Section, depth: float, revolutions_per_second: float,
                slope: float, dynamic_angle_deg: float) -> float:
    """Saeman's (1951) mass flow (kg/s) of a rolling drum bed of ``depth`` (m) at the effective
    axial slope ``slope`` (tan of the incline plus cos(beta) dh/dx; dimensionless), turning at
    ``revolutions_per_second``: rho_b (4/3) pi n (c/2)^3 slope / sin(beta)."""
    c = float(section.chord(depth))
    return (section.bulk_density * 4.0 / 3.0 * math.pi * revolutions_per_second
            * (0.5 * c) ** 3 * slope / math.sin(math.radians(dynamic_angle_deg)))


# ---- the map, as a transport law ----------------------------------------------------------

@dataclass
class MapRow:
    """One slice of the map: hold-up (kg/m), the axial slope tan(theta) of gravity along the
    slice's +axis (gravity's axial component over its component in the section), and each
    figure's steady mean and standard error."""
    holdup: float
    axial_slope: float
    figures: dict                    # name -> (mean, standard error)

    def mean(self, name: str) -> float:
        return self.figures.get(name, (math.nan, 0.0))[0]


def read_map(path) -> tuple[Path, dict]:
    """(the file, its JSON) of a ``map.json`` written by ``taichi-dem map`` (or its folder);
    an unreadable or malformed file is a SceneError naming it."""
    path = Path(path)
    if path.is_dir():
        path = path / "map.json"
    try:
        return path, json.loads(path.read_text())
    except OSError as err:
        raise SceneError(str(path), "", f"cannot read the map: {err.strerror}") from None
    except json.JSONDecodeError as err:
        raise SceneError(str(path), "", f"not a map (JSON): {err}") from None


@dataclass
class MachineMap:
    """A map (the rows of ``taichi-dem map``) and what the march needs of the slice: its
    ``section``, the bodies' angular speeds (rad/s), the mean particle diameter (m), the
    bed material's heat capacity (J/(kg K), None without heat) and the bodies' wall
    temperatures (K, for an isothermal body)."""
    rows: list
    section: Section
    angular_speeds: dict
    particle_diameter: float
    heat_capacity: float | None = None
    wall_temperatures: dict = field(default_factory=dict)
    bodies: list = field(default_factory=list)

    @classmethod
    def load(cls, path) -> "MachineMap":
        """Read a ``map.json`` written by ``taichi-dem map`` (or its folder)."""
        path, doc = read_map(path)
        info = doc.get("machine")
        if not isinstance(info, dict):
            raise SceneError(str(path), "machine", "the map has no 'machine' section (write "
                             "it again with this version of taichi-dem map)")
        rows = []
        for k, row in enumerate(doc.get("rows", [])):
            figures = {}
            for name, value in row.items():
                if name + "_standard_error" in row:
                    se = row[name + "_standard_error"]
                    figures[name] = (float(value), float(se) if se is not None else 0.0)
            rows.append(MapRow(float(row["holdup_kg_per_m"]), float(row.get("axial_slope", info.get("axial_slope", 0.0))),
                               figures))
        if not rows:
            raise SceneError(str(path), "rows", "the map has no rows")
        section = Section(float(info["shell_radius"]), float(info.get("shaft_radius", 0.0)),
                          float(info["bulk_density"]))
        return cls(rows, section, {k: float(v) for k, v in info.get("angular_speeds", {}).items()},
                   float(info["particle_diameter"]), info.get("heat_capacity"),
                   {k: float(v) for k, v in info.get("wall_temperatures", {}).items()},
                   list(info.get("bodies", [])))

    def drawn(self, rng) -> "MachineMap":
        """A copy with every figure drawn from normal(mean, standard error)."""
        rows = [MapRow(r.holdup, r.axial_slope,
                       {n: (m + (rng.normal(0.0, se) if se and math.isfinite(se) else 0.0), se)
                        for n, (m, se) in r.figures.items()}) for r in self.rows]
        return MachineMap(rows, self.section, self.angular_speeds, self.particle_diameter,
                          self.heat_capacity, self.wall_temperatures, self.bodies)


# the smallest share of the flow a depth gradient drives (TransportLaw.bed_share): a bed
# carrying less would need a gradient no bed holds (the flighted slices measured carry 21 - 59 %)
BED_SHARE_FLOOR = 0.05


class TransportLaw:
    """q(H, s) = a(H) + b(H) s (kg/s along the slice's +axis) fitted to the map, a and b held
    as multiples of the chord cubed (Saeman's dependence on the bed, so that a drum's map is
    one constant and hold-ups below the map extrapolate as Saeman's do), interpolated linearly
    in H and held constant beyond the mapped range; beta(H) (deg) likewise, and ``bed_share``
    (phi_bed, the share of the flow a depth gradient drives: module docstring)."""

    def __init__(self, machine: MachineMap, source: str = "map"):
        rows = machine.rows
        holdups = sorted({round(r.holdup, 9) for r in rows})
        slopes = sorted({round(r.axial_slope, 9) for r in rows})
        section = machine.section
        self.section = section
        self.holdups = np.array(holdups)
        self.depths = section.depth(self.holdups)
        chord3 = section.chord(self.depths) ** 3
        a, b, beta, b_error, q_mean = [], [], [], [], []
        for H in holdups:
            at = [r for r in rows if round(r.holdup, 9) == H]
            s = np.array([r.axial_slope for r in at])
            q = np.array([r.mean("axial_mass_flow") for r in at])
            q_mean.append(float(np.mean(q)))
            if len(set(np.round(s, 9))) >= 2:
                slope, icpt = np.polyfit(s, q, 1)
                # the slope's standard error from the rows' (least squares, independent rows)
                se = np.array([r.figures.get("axial_mass_flow", (0.0, 0.0))[1] for r in at])
                ds = s - s.mean()
                b_error.append(float(np.sqrt(np.sum((se * ds) ** 2)) / np.sum(ds * ds)))
            else:       # one incline: a plain drum's law, q proportional to the slope
                if abs(s[0]) < 1e-12:
                    raise SceneError(source, "rows", f"hold-up {H:g} kg/m was mapped only at a "
                                     "level axis: the slope's effect cannot be told (map a "
                                     "second incline)")
                slope, icpt = q[0] / s[0], 0.0
                b_error.append(0.0)
            a.append(icpt)
            b.append(slope)
            angles = [r.mean("dynamic_angle") for r in at]
            angles = [x for x in angles if math.isfinite(x)]
            beta.append(float(np.mean(angles)) if angles else math.nan)
        self.a_per_chord3 = np.array(a) / chord3
        self.b_per_chord3 = np.array(b) / chord3
        beta = np.array(beta)
        if not np.all(np.isfinite(beta)):
            raise SceneError(source, "rows", "the map has no dynamic angle at some hold-up")
        self.beta = beta
        self.single_incline = len(slopes) < 2
        # A self-conveying section whose flow the incline does not measurably change (a screw:
        # b within two standard errors of 0 at every hold-up, negative at some): the bed's
        # surface slope cannot drive it, so its hold-up is where its own flow carries the feed
        # (the limit b -> 0 of the march: the depth jumps to that plateau). Any other b <= 0
        # is refused by the march.
        b, b_error = np.array(b), np.array(b_error)
        self.flow_at_mapped = np.array(q_mean)          # kg/s, mean over the inclines
        # phi_bed: the share of the flow the bed carries, which a depth gradient drives
        # (module docstring); 1 where the map does not say what is carried in flight
        shares = []
        for H in holdups:
            at = [r for r in rows if round(r.holdup, 9) == H]
            parts = [1.0 - r.mean("airborne_mass_flow") / r.mean("axial_mass_flow")
                     for r in at if "airborne_mass_flow" in r.figures
                     and r.mean("axial_mass_flow") != 0.0]
            shares.append(float(np.mean(parts)) if parts and len(parts) == len(at) else 1.0)
        self.bed_share = np.clip(np.array(shares), BED_SHARE_FLOOR, 1.0)
        self.plateau_only = bool(not self.single_incline and np.any(b <= 0.0)
                                 and np.all(np.abs(b) <= 2.0 * b_error))

    def coefficients(self, holdup, depth=None):
        """(a, b, beta_deg) at ``holdup`` (kg/m), whose bed ``depth`` (m) may be given."""
        if depth is None:
            depth = self.section.depth(holdup)[0]
        c3 = float(self.section.chord(depth)) ** 3
        a = float(np.interp(holdup, self.holdups, self.a_per_chord3)) * c3
        b = float(np.interp(holdup, self.holdups, self.b_per_chord3)) * c3
        return a, b, float(np.interp(holdup, self.holdups, self.beta))

    def flow(self, holdup: float, slope: float, depth=None) -> float:
        """q (kg/s along +axis) at ``holdup`` kg/m and effective axial slope ``slope``."""
        a, b, _ = self.coefficients(holdup, depth)
        return a + b * slope

    def direction(self, slope: float) -> int:
        """+1 or -1: where the machine carries its bed at the mapped hold-ups and ``slope``."""
        q = [self.flow(H, slope, d) for H, d in zip(self.holdups, self.depths)]
        return 1 if np.mean(q) >= 0.0 else -1


def _interpolate_figure(machine: MachineMap, name: str, axial_slope: float):
    """(holdups, values) of figure ``name`` at the design slope, anchored at (0, 0) (an empty
    machine: no torque, no heat) and interpolated between the mapped inclines."""
    holdups = sorted({round(r.holdup, 9) for r in machine.rows})
    values = []
    for H in holdups:
        at = [r for r in machine.rows if round(r.holdup, 9) == H and name in r.figures]
        if not at:
            values.append(math.nan)
            continue
        s = np.array([r.axial_slope for r in at])
        v = np.array([r.mean(name) for r in at])
        if len(set(np.round(s, 9))) >= 2:
            k, c = np.polyfit(s, v, 1)
            values.append(float(k * axial_slope + c))
        else:
            values.append(float(v[0]))
    return np.array([0.0] + holdups), np.array([0.0] + values)


# ---- the march ----------------------------------------------------------------------------

@dataclass
class Profile:
    """The machine at one feed: positions ``x`` (m, from the inlet end to the discharge),
    ``depth`` (m) and ``holdup`` (kg/m) there; ``overflows`` when the hold-up passed the
    overflow limit (the profile stops there)."""
    feed: float
    x: np.ndarray
    depth: np.ndarray
    holdup: np.ndarray
    overflows: bool
    flow_sign: int


def march(law: TransportLaw, length: float, feed: float, axial_slope: float,
          discharge_depth: float, overflow_holdup: float, steps: int = 400,
          flow_at=None) -> Profile:
    """The steady hold-up profile of a machine ``length`` m long at ``feed`` kg/s, gravity's
    axial slope ``axial_slope`` along the slice's +axis, from the discharge (bed depth
    ``discharge_depth`` m: a dam's height, or a few particles for a free discharge) upstream,
    by RK4 in the bed depth: dh/dx_up = ((F - a)/b - s_d) / (phi_bed cos(beta)), s_d the slope
    towards the discharge, phi_bed the share of the flow the bed carries (1 without the map's
    airborne_mass_flow). ``flow_at``: F at a distance (m) from the discharge, where the feed
    enters over a stretch (feed_entered); default ``feed`` all along."""
    # the flow direction: where the machine carries its bed at the mapped hold-ups
    sign = law.direction(axial_slope)
    s_down = sign * axial_slope
    section = law.section
    if law.plateau_only:
        return _plateau(law, length, feed, overflow_holdup, sign, steps)

    # the law tabulated on a fine grid of depths (the march evaluates it ~4 x steps times)
    cells = 4000
    table_u = np.linspace(1e-6, 1.0, cells + 1)
    table_h = table_u ** 2 * 2.0 * section.shell_radius
    table_H = section.holdup(table_h)
    ha, hb, hbeta, hshare = (np.interp(table_H, law.holdups, v)
                             for v in (law.a_per_chord3, law.b_per_chord3, law.beta,
                                       law.bed_share))
    c3 = section.chord(table_h) ** 3
    a_down = sign * ha * c3          # a along the flow; b (dq/ds) is the same either way
    b = hb * c3
    if np.any(hb <= 0.0):
        raise SceneError("map", "rows", "the map's flow falls with the slope (b <= 0) at some "
                         "hold-up: not a transport law the march can use")
    # the gradient drives the bed's share of the flow only (module docstring)
    inv_cos = 1.0 / (np.cos(np.radians(hbeta)) * hshare)
    two_r, du = 2.0 * section.shell_radius, table_u[1] - table_u[0]

    def rate(h, flow):
        # Kramers' dh/dx is singular on an empty shell: the table starts just above it
        k = min(max(math.sqrt(h / two_r) - 1e-6, 0.0) / du, cells - 1e-9)
        i = int(k)
        w = k - i
        aa = a_down[i] * (1 - w) + a_down[i + 1] * w
        bb = b[i] * (1 - w) + b[i + 1] * w
        return ((flow - aa) / bb - s_down) * (inv_cos[i] * (1 - w) + inv_cos[i + 1] * w)

    # positions from the discharge on a grid fine where the bed is shallow and steep
    grid = length * (np.arange(steps + 1) / steps) ** 2
    h = float(discharge_depth)
    up = [0.0]
    depths = [h]
    full = float(section.depth(overflow_holdup)[0])
    overflows = False
    if flow_at is None:
        def flow_at(_):
            return feed
    for k in range(steps):
        dx = grid[k + 1] - grid[k]
        f0, fm, f1 = flow_at(grid[k]), flow_at(grid[k] + 0.5 * dx), flow_at(grid[k + 1])
        k1 = rate(h, f0)
        k2 = rate(max(h + 0.5 * dx * k1, 0.0), fm)
        k3 = rate(max(h + 0.5 * dx * k2, 0.0), fm)
        k4 = rate(max(h + dx * k3, 0.0), f1)
        h = max(h + dx / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4), 0.0)
        up.append(grid[k + 1])
        depths.append(h)
        if h > full * (1.0 + 1e-9):
            overflows = True
            break
    up = np.array(up)
    depths = np.array(depths)
    x = length - up[::-1]          # from the inlet end
    depths = depths[::-1]
    return Profile(feed, x, depths, section.holdup(depths), overflows, sign)


def _plateau(law: TransportLaw, length: float, feed: float, overflow_holdup: float, sign: int,
             steps: int) -> Profile:
    """A section at the hold-up whose own flow carries ``feed`` (TransportLaw.plateau_only):
    the mapped flows (mean over the inclines, from 0 at an empty section) interpolated; beyond
    the largest mapped flow, or above ``overflow_holdup``, it overflows."""
    holdups = np.concatenate([[0.0], law.holdups])
    flows = np.concatenate([[0.0], sign * law.flow_at_mapped])
    if np.any(np.diff(flows) <= 0.0):
        raise SceneError("map", "rows", "the section's flow does not rise with its hold-up: no "
                         "hold-up carries a given feed")
    overflows = feed > flows[-1] or float(np.interp(feed, flows, holdups)) > overflow_holdup * (1 + 1e-9)
    held = min(float(np.interp(feed, flows, holdups)), overflow_holdup)
    x = np.linspace(0.0, length, steps + 1)
    depth = np.full_like(x, float(law.section.depth(held)[0]))
    return Profile(feed, x, depth, law.section.holdup(depth), overflows, sign)


def _integral(x, y) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


@dataclass
class MachineAnswer:
    """What the march gives at one feed (kg/s): hold-up (kg), mean residence (s), each body's
    torque (N m) and power (W), outlet temperature (K) and the inlet-end hold-up (kg/m)."""
    feed: float
    holdup: float
    residence_time: float
    inlet_holdup: float
    torques: dict
    powers: dict
    outlet_temperature: float | None
    overflows: bool
    profile: Profile


def _pieces(machine: MachineMap, length: float, inlet_sections, law=None) -> list:
    """[(map, length m, law)] from the discharge upstream: ``machine`` over what the
    ``inlet_sections`` ((map, length), in order from the inlet end) leave at the discharge end."""
    inlet_sections = list(inlet_sections or ())
    rest = length - sum(l for _, l in inlet_sections)
    if rest <= 0.0:
        raise SceneError("taichi-dem machine", "--inlet-section", f"the inlet sections are "
                         f"{length - rest:g} m long, not shorter than the machine ({length:g} m)")
    return [(machine, rest, law or TransportLaw(machine))] + [
        (m, l, TransportLaw(m, source=f"inlet section {k + 1}"))
        for k, (m, l) in reversed(list(enumerate(inlet_sections)))]


def feed_entered(feed: float, length: float, feed_over=None):
    """F(distance from the discharge, m) -> kg/s: the flow past a cross-section when the feed
    enters evenly between ``feed_over`` = (x0, x1) m from the inlet end (a factory's box, a
    chute's spread): 0 upstream of x0, all of it from x1 on. None: ``feed`` everywhere (the
    feed dropped at the inlet end)."""
    if feed_over is None:
        return lambda up: feed
    x0, x1 = (float(v) for v in feed_over)
    if not 0.0 <= x0 < x1 <= length:
        raise SceneError("taichi-dem machine", "--feed-over", f"the feed's stretch {x0:g} - "
                         f"{x1:g} m must lie within the machine's {length:g} m, its start first")
    return lambda up: feed * min(max((length - up - x0) / (x1 - x0), 0.0), 1.0)


def _march_pieces(pieces, feed: float, axial_slope: float, depth0: float,
                  overflow_holdup: float | None, steps: int, feed_over=None) -> list:
    """March each piece from the discharge upstream, the bed's depth (its free surface)
    continuous where one section meets the next; [(map, x offset m, profile)], stopping at the
    first that overflows. Every section must carry the bed the same way."""
    out = []
    depth = depth0
    total = sum(l for _, l, _ in pieces)
    done = 0.0
    signs = {law.direction(axial_slope) for _, _, law in pieces}
    if len(signs) > 1:
        raise SceneError("taichi-dem machine", "--inlet-section", "the sections' maps carry the "
                         "bed in opposite directions at this incline")
    entered = feed_entered(feed, total, feed_over)
    for m, piece_length, law in pieces:
        limit = float(law.holdups[-1]) if overflow_holdup is None else overflow_holdup
        prof = march(law, piece_length, feed, axial_slope, depth, limit, steps,
                     flow_at=lambda up, start=done: entered(start + up))
        done += piece_length
        out.append((m, total - done, prof))
        if prof.overflows:
            break
        depth = float(prof.depth[0])            # at this piece's upstream end
    return out


def answer(machine: MachineMap, length: float, feed: float, axial_slope: float,
           discharge_depth: float | None = None, overflow_holdup: float | None = None,
           inlet_temperature: float | None = None, law: TransportLaw | None = None,
           steps: int = 400, inlet_sections=(), feed_over=None) -> MachineAnswer:
    """The machine ``length`` m long at ``feed`` kg/s: march and integrate (module docstring).
    ``discharge_depth`` defaults to one particle diameter, ``overflow_holdup`` to the largest
    mapped hold-up (of each section's map). ``inlet_sections``: [(map, length m)] in order
    from the inlet end, each with its own map (an inlet screw before the paddles); ``machine``
    covers the rest, at the discharge end. Each section's figures come from its own map; a
    body's torque and power are summed over the sections that have it (by name).
    ``feed_over``: (x0, x1) m from the inlet end where the feed enters evenly (feed_entered);
    default at the inlet end."""
    pieces = _pieces(machine, length, inlet_sections, law)
    depth0 = machine.particle_diameter if discharge_depth is None else discharge_depth
    marched = _march_pieces(pieces, feed, axial_slope, depth0, overflow_holdup, steps,
                            feed_over)
    hold = 0.0
    torques, powers = {}, {}
    ntu, wall = 0.0, None
    for m, _, prof in marched:
        hold += _integral(prof.x, prof.holdup)
        for body in m.bodies:
            for name, out in (("torque_per_metre", torques), ("power_per_metre", powers)):
                hs, vs = _interpolate_figure(m, f"{body}/{name}", axial_slope)
                if np.all(np.isfinite(vs)):
                    out[body] = out.get(body, 0.0) + _integral(prof.x, np.interp(prof.holdup, hs, vs))
        if inlet_temperature is not None and m.heat_capacity:
            for body in m.bodies:
                hs, vs = _interpolate_figure(m, f"{body}/conductance_per_metre", axial_slope)
                if body in m.wall_temperatures and np.all(np.isfinite(vs)):
                    ntu += _integral(prof.x, np.interp(prof.holdup, hs, vs)) / (feed * m.heat_capacity)
                    wall = m.wall_temperatures[body] if wall is None else wall
    t_out = None
    if wall is not None:
        t_out = wall + (inlet_temperature - wall) * math.exp(-ntu)
    # one profile from the inlet end: the pieces upstream first
    parts = marched[::-1]
    x = np.concatenate([offset + prof.x for _, offset, prof in parts])
    depth = np.concatenate([prof.depth for _, _, prof in parts])
    holdup = np.concatenate([prof.holdup for _, _, prof in parts])
    overflows = any(prof.overflows for _, _, prof in marched)
    prof = Profile(feed, x, depth, holdup, overflows, marched[0][2].flow_sign)
    return MachineAnswer(feed, hold, hold / feed, float(prof.holdup[0]), torques, powers, t_out,
                         prof.overflows, prof)


def capacity(machine: MachineMap, length: float, axial_slope: float,
             discharge_depth: float | None = None, overflow_holdup: float | None = None,
             law: TransportLaw | None = None, steps: int = 200, inlet_sections=(),
             feed_over=None) -> float:
    """The largest feed (kg/s) whose profile stays below the overflow hold-up of every section
    (bisection); ``feed_over`` as answer()'s."""
    pieces = _pieces(machine, length, inlet_sections, law)
    law = pieces[0][2]
    limit = float(law.holdups[-1]) if overflow_holdup is None else overflow_holdup

    slope_sign = law.direction(axial_slope)
    depth0 = machine.particle_diameter if discharge_depth is None else discharge_depth

    def fits(feed):
        return not any(prof.overflows for _, _, prof in
                       _march_pieces(pieces, feed, axial_slope, depth0, overflow_holdup, steps,
                                     feed_over))
    # the feed whose uniform bed sits at the overflow brackets the capacity (a short machine
    # with a shallow discharge holds more)
    uniform = max(slope_sign * law.flow(limit, axial_slope), 1e-12)
    lo, hi = 0.0, 2.0 * uniform
    while fits(hi) and hi < 1e3 * uniform:
        lo, hi = hi, 2.0 * hi
    if fits(hi):
        return hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if fits(mid):
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-3 * hi:
            break
    return lo


def with_errors(machine: MachineMap, length: float, feeds, axial_slope: float,
                discharge_depth=None, overflow_holdup=None, inlet_temperature=None,
                draws: int = 40, seed: int = 0, inlet_sections=(), feed_over=None) -> dict:
    """The answers at each feed and the capacity, each with the standard deviation over
    ``draws`` re-marches of maps (every section's) drawn from the figures' standard errors."""
    rng = np.random.default_rng(seed)
    inlet_sections = list(inlet_sections or ())
    base = {"capacity": capacity(machine, length, axial_slope, discharge_depth, overflow_holdup,
                                 inlet_sections=inlet_sections, feed_over=feed_over),
            "feeds": [answer(machine, length, f, axial_slope, discharge_depth, overflow_holdup,
                             inlet_temperature, inlet_sections=inlet_sections,
                             feed_over=feed_over) for f in feeds]}
    samples = {"capacity": [], "feeds": [[] for _ in feeds]}
    bodies = list(dict.fromkeys([*machine.bodies, *(b for m, _ in inlet_sections for b in m.bodies)]))
    for _ in range(draws):
        drawn = machine.drawn(rng)
        drawn_inlet = [(m.drawn(rng), l) for m, l in inlet_sections]
        try:
            law = TransportLaw(drawn)
            samples["capacity"].append(capacity(drawn, length, axial_slope, discharge_depth,
                                                overflow_holdup, law=law,
                                                inlet_sections=drawn_inlet,
                                                feed_over=feed_over))
            for k, f in enumerate(feeds):
                samples["feeds"][k].append(answer(drawn, length, f, axial_slope, discharge_depth,
                                                  overflow_holdup, inlet_temperature, law=law,
                                                  inlet_sections=drawn_inlet,
                                                  feed_over=feed_over))
        except SceneError:        # a draw whose flow falls with the slope: skipped
            continue
    base["capacity_error"] = float(np.std(samples["capacity"], ddof=1)) if len(samples["capacity"]) > 1 else math.nan
    errors = []
    for answers in samples["feeds"]:
        e = {}
        if len(answers) > 1:
            e["holdup"] = float(np.std([a.holdup for a in answers], ddof=1))
            e["residence_time"] = float(np.std([a.residence_time for a in answers], ddof=1))
            for body in bodies:
                vals = [a.torques[body] for a in answers if body in a.torques]
                if len(vals) > 1:
                    e[f"{body}/torque"] = float(np.std(vals, ddof=1))
                vals = [a.powers[body] for a in answers if body in a.powers]
                if len(vals) > 1:
                    e[f"{body}/power"] = float(np.std(vals, ddof=1))
            temps = [a.outlet_temperature for a in answers if a.outlet_temperature is not None]
            if len(temps) > 1:
                e["outlet_temperature"] = float(np.std(temps, ddof=1))
        errors.append(e)
    base["errors"] = errors
    base["draws"] = len(samples["capacity"])
    return base


_HOLDUP = re.compile(r"^\s*([0-9.eE+-]+)\s*(kg/m|%)?\s*$")


def substituted(base: MachineMap, other: MachineMap, source: str = "--choice") -> MachineMap:
    """``base`` with the rows of ``other`` (the same slice with one modelling choice changed:
    precision, particle size, time scale) put in: a base row that ``other`` mapped at the same
    hold-up and incline takes ``other``'s figures; one that ``other`` mapped at the same
    hold-up but another incline only is shifted by the choice's difference there (each figure
    + other - base at that incline: the choice moves a(H) and the per-metre figures, and its
    effect on the slope's b(H) is taken as nil). The particle diameter is ``other``'s. A
    hold-up ``other`` did not map is refused: the march would mix the two."""
    def key(r):
        return round(r.holdup, 6), round(r.axial_slope, 9)
    theirs = {key(r): r for r in other.rows}
    mine = {key(r): r for r in base.rows}
    rows = []
    for r in base.rows:
        if key(r) in theirs:
            rows.append(MapRow(r.holdup, r.axial_slope, dict(theirs[key(r)].figures)))
            continue
        pairs = [(k, o) for k, o in theirs.items() if k[0] == key(r)[0] and k in mine]
        if not pairs:
            raise SceneError(source, "rows", f"the map lacks the hold-up {r.holdup:g} kg/m that "
                             "the main map has: map the choice at the same hold-ups")
        k, o = pairs[0]
        ref = mine[k]
        figures = {}
        for name, (value, se) in r.figures.items():
            if name in o.figures and name in ref.figures:
                figures[name] = (value + o.figures[name][0] - ref.figures[name][0],
                                 float(math.hypot(se, o.figures[name][1])))
            else:
                figures[name] = (value, se)
        rows.append(MapRow(r.holdup, r.axial_slope, figures))
    return MachineMap(rows, base.section, base.angular_speeds, other.particle_diameter,
                      other.heat_capacity, base.wall_temperatures, base.bodies)


def choice_differences(base_out: dict, choice_out: dict) -> dict:
    """Each answer's change under a modelling choice (choice - base) with z = change over the
    two re-march deviations combined; ``base_out``/``choice_out`` are ``with_errors``'."""
    def diff(a, ea, b, eb):
        if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
            return None
        e = math.hypot(ea if ea is not None and math.isfinite(ea) else 0.0,
                       eb if eb is not None and math.isfinite(eb) else 0.0)
        # relative to the answer itself: +10 % is 10 % more of it (a torque that is negative,
        # the particles' on the body, grows in size by 10 %)
        return {"change": b - a, "relative": (b - a) / a if a else math.nan,
                "z": (b - a) / e if e > 0 else math.nan}
    out = {"capacity": diff(base_out["capacity"], base_out["capacity_error"],
                            choice_out["capacity"], choice_out["capacity_error"]), "feeds": []}
    for a, ea, b, eb in zip(base_out["feeds"], base_out["errors"], choice_out["feeds"],
                            choice_out["errors"]):
        row = {"feed_kg_per_s": a.feed,
               "residence_time": diff(a.residence_time, ea.get("residence_time"),
                                      b.residence_time, eb.get("residence_time")),
               "holdup": diff(a.holdup, ea.get("holdup"), b.holdup, eb.get("holdup")),
               "outlet_temperature": diff(a.outlet_temperature, ea.get("outlet_temperature"),
                                          b.outlet_temperature, eb.get("outlet_temperature"))}
        for body in a.torques:
            if body in b.torques:
                row[f"{body}/torque"] = diff(a.torques[body], ea.get(f"{body}/torque"),
                                             b.torques[body], eb.get(f"{body}/torque"))
        out["feeds"].append(row)
    return out


def choices_report(differences: dict) -> str:
    """Markdown: what each modelling choice moves each answer by (``choice_differences``)."""
    def cell(d, scale=1.0, percent=True):
        if d is None:
            return "n/a"
        if not percent:       # a temperature: its change in K says it, a % of K does not
            return f"{d['change'] * scale:+.3g} (z {d['z']:+.1f})"
        return f"{d['change'] * scale:+.3g} ({100 * d['relative']:+.0f} %, z {d['z']:+.1f})"
    bodies = []
    for d in differences.values():
        for row in d["feeds"]:
            bodies += [n for n in row if n.endswith("/torque") and n not in bodies]
    lines = ["## What each modelling choice moves the answers by", "",
             "each cell: the answer with the choice minus without, in % of the answer, and z = "
             "the change over the two re-march deviations combined (|z| > 2: beyond the maps' "
             "noise); torques are the particles' on each body (N m)", "",
             "| choice | feed (t/h) | capacity (t/h) | mean residence (s) | "
             + "".join(f"{b} (N m) | " for b in bodies) + "outlet temperature (K) |",
             "|---" * (5 + len(bodies)) + "|"]
    for label, d in differences.items():
        for k, row in enumerate(d["feeds"]):
            lines.append(f"| {label} | {row['feed_kg_per_s'] * 3.6:.3g} | "
                         + (cell(d["capacity"], 3.6) if k == 0 else "") + " | "
                         + cell(row["residence_time"]) + " | "
                         + "".join(cell(row.get(b)) + " | " for b in bodies)
                         + cell(row["outlet_temperature"], percent=False) + " |")
    return "\n".join(lines)


def parse_holdup(text: str) -> tuple[str, float]:
    """``"60 kg/m"`` -> ("kg/m", 60.0); ``"25 %"`` -> ("fill", 0.25); a bare number is kg/m."""
    m = _HOLDUP.match(str(text))
    if not m:
        raise ValueError(f"hold-up {text!r}: give kg/m (e.g. '60 kg/m') or a fill fraction "
                         "of the free section (e.g. '25 %')")
    value = float(m.group(1))
    if m.group(2) == "%":
        return "fill", value / 100.0
    return "kg/m", value


def saeman_check(row: dict, info: dict) -> tuple[float, float]:
    """(Saeman's mass flow kg/s along +axis, the map's flow over it) for a map ``row`` of a
    drum (the shell turning): Saeman's uniform-bed flow at the row's incline and measured
    dynamic angle, the bed's chord from its hold-up at the map's bulk density. (nan, nan)
    when the shell does not turn or the angle is missing."""
    shell = info.get("shell")
    omega = abs(info.get("angular_speeds", {}).get(shell, 0.0))
    beta = row.get("dynamic_angle", math.nan)
    if omega == 0.0 or not math.isfinite(beta) or beta <= 0.0 or shell is None:
        return math.nan, math.nan
    section = Section(info["shell_radius"], info.get("shaft_radius", 0.0), info["bulk_density"])
    # the chord of the hold-up at the map's bulk density: the measured surface chord runs
    # through the top layer's highest centres, an envelope above the mean surface (the solid
    # fraction under it comes out at 0.44 in a rolling bed of spheres: too low to be the bed)
    depth = float(section.depth(row["holdup_kg_per_m"])[0])
    # gravity's pull towards -axis (positive incline) carries the bed towards -x
    q = -saeman_flow(section, depth, omega / (2.0 * math.pi), math.tan(math.radians(
        row.get("incline_deg", 0.0))), beta)
    return q, row["axial_mass_flow"] / q if q else math.nan


# ---- taichi-dem machine -------------------------------------------------------------------
