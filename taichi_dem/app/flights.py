"""Flight unloading in a flighted drum: how much a lifting flight holds against its angular
position, measured in a slice (`taichi-dem map`) and predicted by the geometric model of the
rotary-dryer literature (PHYSICS.md, "Flighted rotary dryers").

The geometric model (Kelly & O'Donnell 1977; Baker 1988; Sunkara et al. 2013): a flight holds
the solids that lie between its plate (the radial leg and the lip), the shell, and a free
surface through the lip's tip at the kinetic angle of repose gamma. Schofield & Glikin (1962)
give gamma from a force balance on a particle rolling on that surface in the rotating drum:

    tan(gamma) = (mu + Fr (cos(delta) - mu sin(delta))) / (1 - Fr (sin(delta) + mu cos(delta)))

with mu the solids' dynamic friction coefficient (tan of their angle of repose), Fr = w^2 r / g
at the tip's radius r, and delta the flight's angle above the horizontal on the rising side
(0: the leg horizontal, pointing at the axis; 90 deg: at the top). The flight is empty past the
final discharge angle, where the surface through the tip leaves no solids behind it.

Angles here are in the drum's cross-section, seen so that the drum turns counter-clockwise:
from the rising side's horizontal (h) towards up (u). A drum turning the other way is mirrored.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# the profile's bins of flight angle (deg, above the rising side's horizontal)
BIN_WIDTH_DEG = 7.5
# the measured final discharge angle: the first bin whose mean load is below this fraction of
# the first bin's
EMPTY_BELOW = 0.05


@dataclass(frozen=True)
class Flights:
    """Lifting flights on a drum's shell: ``count`` evenly spaced, the first at ``phase``
    (rad, from the cross-section's horizontal towards up at t = 0), a radial leg of ``height``
    (m) from the shell of ``radius`` (m), and a lip of ``lip`` m (0: a straight flight) at
    ``lip_angle`` (rad) to the leg, pointing ahead (the leading side)."""
    count: int
    radius: float
    height: float
    lip: float = 0.0
    lip_angle: float = math.pi / 2
    phase: float = 0.0

    def tip(self, delta: float) -> np.ndarray:
        """The lip's tip (m, in the cross-section: horizontal, up) of a flight at ``delta``."""
        e_r, e_t = _frame(delta)
        return ((self.radius - self.height - self.lip * math.cos(self.lip_angle)) * e_r
                + self.lip * math.sin(self.lip_angle) * e_t)


def flights_of(mesh: dict, rotation_sense: float) -> Flights | None:
    """The flights of a ``drum`` builder's mesh table (a scene's ``bodies[i].mesh``), or None
    without flights or with lips that trail the rotation (``rotation_sense``: the sign of the
    drum's speed about its axis): the geometric model holds for leading lips and straight
    flights."""
    if not isinstance(mesh, dict) or mesh.get("builder") != "drum":
        return None
    count = int(mesh.get("flights", 0) or 0)
    if count <= 0 or mesh.get("flight_height") is None:
        return None
    from ..scene.units import parse_quantity
    radius = float(parse_quantity(mesh["radius"], "length"))
    height = float(parse_quantity(mesh["flight_height"], "length"))
    lip = 0.0
    if mesh.get("flight_shape", "straight") == "L":
        lip = float(parse_quantity(mesh["flight_lip"], "length"))
        leading = mesh.get("flight_lip_side", "leading") == "leading"
        if leading != (rotation_sense > 0):
            return None
    phase = math.radians(float(mesh.get("flight_phase_deg", 0.0)))
    return Flights(count, radius, height, lip,
                   math.radians(float(mesh.get("flight_lip_angle_deg", 90.0))),
                   # mirrored (the horizontal reversed) for a drum turning the other way
                   phase if rotation_sense > 0 else math.pi - phase)


def _frame(delta: float) -> tuple[np.ndarray, np.ndarray]:
    """The flight's radial (out of the axis) and tangential (ahead) unit vectors at delta."""
    return (np.array([math.cos(delta), math.sin(delta)]),
            np.array([-math.sin(delta), math.cos(delta)]))


def kinetic_angle(delta, mu: float, froude: float):
    """Schofield & Glikin's angle of the solids' surface in a flight (rad) at flight angle
    ``delta`` (rad; arrays too), dynamic friction ``mu`` and ``froude`` = w^2 r_tip / g."""
    delta = np.asarray(delta, float)
    top = mu + froude * (np.cos(delta) - mu * np.sin(delta))
    bottom = 1.0 - froude * (np.sin(delta) + mu * np.cos(delta))
    return np.arctan2(top, bottom)


def _clip(polygon: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """The part of convex ``polygon`` ((n, 2), in order) where normal . p <= offset
    (Sutherland-Hodgman against one half-plane)."""
    if len(polygon) == 0:
        return polygon
    side = polygon @ normal - offset
    out = []
    n = len(polygon)
    for i in range(n):
        a, b = polygon[i], polygon[(i + 1) % n]
        sa, sb = side[i], side[(i + 1) % n]
        if sa <= 0.0:
            out.append(a)
        if (sa < 0.0 < sb) or (sb < 0.0 < sa):
            out.append(a + (b - a) * (sa / (sa - sb)))
    return np.asarray(out).reshape(-1, 2)


def _area(polygon: np.ndarray) -> float:
    if len(polygon) < 3:
        return 0.0
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def holdup_area(flights: Flights, delta: float, gamma: float, segments: int = 2048) -> float:
    """The cross-section (m^2) of the solids a full flight holds at ``delta`` (rad) with its
    surface at ``gamma`` (rad) through the tip: the shell's disc (a polygon of ``segments``
    sides) cut to the leading side of the leg, the shell side of the lip's line, the rising
    side of the tip and below the surface (PHYSICS.md; module docstring). In a counter-clockwise
    drum every free surface rises towards the rising side (+h), so the surface through the tip
    is the line rising at gamma towards +h."""
    e_r, e_t = _frame(delta)
    R, tip = flights.radius, flights.tip(delta)
    phi = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    # a polygon circumscribing nothing beyond the circle: vertices on it (error ~ R^2/segments^2)
    region = R * np.column_stack([np.cos(phi), np.sin(phi)])
    region = _clip(region, -e_t, 0.0)                                    # ahead of the leg
    if flights.lip > 0.0:
        # the lip's line, from the leg's tip to the lip's tip; keep the side of the shell
        junction = (R - flights.height) * e_r
        along = (tip - junction) / np.linalg.norm(tip - junction)
        normal = np.array([along[1], -along[0]])
        if normal @ (R * e_r - junction) > 0.0:
            normal = -normal
        region = _clip(region, normal, float(normal @ junction))
    else:
        region = _clip(region, -e_r, -(R - flights.height))             # outside the tip's radius
    region = _clip(region, np.array([-1.0, 0.0]), -float(tip[0]))      # on the rising side of the tip
    up = np.array([-math.sin(gamma), math.cos(gamma)])                 # the surface's upward normal
    region = _clip(region, up, float(up @ tip))
    return _area(region)


def model_profile(flights: Flights, deltas, mu: float, froude: float) -> np.ndarray:
    """A full flight's cross-section held (m^2) at each flight angle in ``deltas`` (rad): the
    geometric model with Schofield & Glikin's surface, zero from the final discharge angle on
    (the first angle past 0 at which the flight holds nothing: a flight does not refill)."""
    deltas = np.asarray(deltas, float)
    out = np.zeros(len(deltas))
    empty = final_discharge_angle(flights, mu, froude)
    for i, d in enumerate(deltas):
        if d < empty:
            out[i] = holdup_area(flights, d, float(kinetic_angle(d, mu, froude)))
    return out


def final_discharge_angle(flights: Flights, mu: float, froude: float) -> float:
    """The flight angle (rad) at which a flight's load runs out in the geometric model (the
    first past 0; bisection to 1e-6 rad after a scan in 0.5 deg steps)."""
    def held(d):
        return holdup_area(flights, d, float(kinetic_angle(d, mu, froude)), segments=512)
    steps = np.radians(np.arange(0.0, 270.0, 0.5))
    previous = 0.0
    for d in steps:
        if held(d) <= 1e-12 * flights.radius ** 2:
            lo, hi = previous, d
            while hi - lo > 1e-6:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if held(mid) > 1e-12 * flights.radius ** 2 else (lo, mid)
            return 0.5 * (lo + hi)
        previous = d
    return float(steps[-1])


def flight_loads(position_hu: np.ndarray, mass: np.ndarray, held: np.ndarray,
                 flights: Flights, turned: float) -> tuple[np.ndarray, np.ndarray]:
    """Each flight's angle (rad, wrapped to [-pi, pi)) and load (kg) now (``position_hu``:
    (N, 2) m in the cross-section, horizontal and up from the axis; ``turned``: rad the drum
    has turned since t = 0, counter-clockwise). A flight's load is the mass of the particles in
    ``held`` (touching a particle or a body: not airborne) whose centres lie where the
    geometric model puts its solids before the surface cuts them (holdup_area): ahead of its
    leg and behind the next flight's, on the shell's side of its lip's line and on the rising
    side of its tip. (Solids that pour off a tip onto the back of the next flight, and
    rest there once it turns past the top, lie beyond that tip.)"""
    pitch = 2.0 * math.pi / flights.count
    angles = np.mod(flights.phase + turned + pitch * np.arange(flights.count) + math.pi,
                    2.0 * math.pi) - math.pi
    theta = np.arctan2(position_hu[:, 1], position_hu[:, 0])
    R = flights.radius
    loads = np.zeros(flights.count)
    for k, a in enumerate(angles):
        inside = held & (np.mod(theta - a, 2.0 * math.pi) < pitch)
        e_r, e_t = _frame(float(a))
        tip = flights.tip(float(a))
        inside &= position_hu[:, 0] >= tip[0]
        if flights.lip > 0.0:
            junction = (R - flights.height) * e_r
            along = (tip - junction) / np.linalg.norm(tip - junction)
            normal = np.array([along[1], -along[0]])
            if normal @ (R * e_r - junction) < 0.0:
                normal = -normal
            inside &= (position_hu - junction) @ normal >= 0.0
        else:
            inside &= position_hu @ e_r >= R - flights.height
        loads[k] = float(np.sum(mass[inside]))
    return angles, loads


def unloading_profile(angles, loads, length: float, bulk_density: float,
                      flights: Flights, froude: float) -> dict:
    """The measured unloading curve from every sample's (flight angle rad, load kg) over a
    slice of ``length`` m: per BIN_WIDTH_DEG bin from 0 deg, the mean load (kg/m) and its
    standard error; the load as a cross-section (m^2, at ``bulk_density`` kg/m^3); the
    geometric model fitted in mu (least squares on the cross-sections, one parameter) with the
    root-mean-square difference over the full flight's load; and the final discharge angles,
    measured (the first bin below EMPTY_BELOW of the first bin's load) and modelled."""
    from scipy.optimize import minimize_scalar
    angles = np.asarray(angles, float)
    loads = np.asarray(loads, float) / length
    edges = np.arange(0.0, 180.0 + BIN_WIDTH_DEG, BIN_WIDTH_DEG)
    deg = np.degrees(angles)
    centres, means, errors, counts = [], [], [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = loads[(deg >= lo) & (deg < hi)]
        if len(inside) < 2:
            continue
        centres.append(0.5 * (lo + hi))
        means.append(float(np.mean(inside)))
        errors.append(float(np.std(inside, ddof=1) / math.sqrt(len(inside))))
        counts.append(int(len(inside)))
    out = {"flight_angle_deg": centres, "load_kg_per_m": means,
           "load_standard_error": errors, "samples": counts, "bulk_density": bulk_density,
           "froude": froude}
    if len(centres) < 4 or means[0] <= 0.0:
        return out
    measured = np.asarray(means) / bulk_density
    where = np.radians(centres)

    def misfit(mu):
        return float(np.sum((model_profile(flights, where, mu, froude) - measured) ** 2))
    best = minimize_scalar(misfit, bounds=(0.05, 2.0), method="bounded",
                           options={"xatol": 1e-4})
    mu = float(best.x)
    model = model_profile(flights, where, mu, froude)
    full = float(holdup_area(flights, 0.0, float(kinetic_angle(0.0, mu, froude))))
    below = [c for c, m in zip(centres, means) if m < EMPTY_BELOW * means[0]]
    out.update({"fitted_friction": mu, "kinetic_angle_at_0_deg": math.degrees(
                    float(kinetic_angle(0.0, mu, froude))),
                "model_area_m2": model.tolist(), "full_flight_area_m2": full,
                "rms_difference_of_full": math.sqrt(float(np.mean((model - measured) ** 2))) / full,
                "final_discharge_angle_deg": below[0] if below else math.nan,
                "model_final_discharge_angle_deg": math.degrees(
                    final_discharge_angle(flights, mu, froude))})
    return out


class FlightRecorder:
    """Samples the loads of a slice's flights (SliceObserver calls :meth:`sample` at every
    sample) and reduces them to the unloading profile (:meth:`profile`)."""

    def __init__(self, flights: Flights, axis_point, axis_direction, up, horizontal,
                 sense: float, gravity_across: float, omega: float):
        self.flights = flights
        self.point = np.asarray(axis_point, float)
        self.axis = np.asarray(axis_direction, float)
        self.up = np.asarray(up, float)
        # mirrored for a drum turning clockwise in (horizontal, up): counter-clockwise here
        self.horizontal = np.asarray(horizontal, float) * (1.0 if sense > 0 else -1.0)
        tip = flights.tip(0.0)
        self.froude = omega ** 2 * float(np.linalg.norm(tip)) / gravity_across
        self.angles: list[float] = []
        self.loads: list[float] = []
        self.samples: list[int] = []          # the sample each entry is from
        self._count = 0

    @classmethod
    def for_slice(cls, sim, geometry, mesh: dict, up, horizontal):
        """A recorder for the slice's shell body (``geometry.shell``) when its mesh table is a
        ``drum`` with flights turning about the slice's axis, else None."""
        body = sim.scene.bodies[geometry.shell]
        speed = body.motion.speed.at(0.0) if body.motion.speed is not None else 0.0
        along = float(np.asarray(body.motion.axis_direction, float) @ geometry.axis_direction)
        if speed == 0.0 or abs(abs(along) - 1.0) > 1e-9 or geometry.axis != 0:
            return None
        # the builder's frame must be the slice's: the drum along +x about the turning axis
        if float(mesh.get("incline_deg", 0.0) or 0.0) != 0.0:
            return None
        if mesh.get("axis_direction") is not None and \
                not np.allclose(np.asarray(mesh["axis_direction"], float), [1.0, 0.0, 0.0]):
            return None
        origin = np.asarray(mesh.get("origin", [0.0, 0.0, 0.0]), float)
        if not np.allclose(origin[1:], np.asarray(geometry.axis_point, float)[1:], atol=1e-9):
            return None
        sense = math.copysign(1.0, speed * along)
        flights = flights_of(mesh, sense)
        if flights is None:
            return None
        g = np.asarray(sim.scene.simulation.gravity, float)
        across = float(np.linalg.norm(g - (g @ geometry.axis_direction) * geometry.axis_direction))
        return cls(flights, geometry.axis_point, geometry.axis_direction, up, horizontal,
                   sense, across, abs(speed))

    def sample(self, position: np.ndarray, mass: np.ndarray, held: np.ndarray,
               rotation: np.ndarray) -> None:
        """Record each flight above the horizontal: its angle and load (flight_loads) with the
        shell at ``rotation`` (its pose's R)."""
        turned_h = rotation @ self.horizontal
        turned = math.atan2(float(turned_h @ self.up), float(turned_h @ self.horizontal))
        rel = np.asarray(position, float) - self.point
        hu = np.column_stack([rel @ self.horizontal, rel @ self.up])
        angles, loads = flight_loads(hu, np.asarray(mass, float), held, self.flights, turned)
        keep = angles >= 0.0
        self.angles += angles[keep].tolist()
        self.loads += loads[keep].tolist()
        self.samples += [self._count] * int(np.sum(keep))
        self._count += 1

    def profile(self, length: float, bulk_density: float, start: int = 0) -> dict:
        """The unloading profile (unloading_profile) of the samples from sample ``start`` on
        (the steady part of the run), over a slice of ``length`` m."""
        keep = np.asarray(self.samples, int) >= start
        out = unloading_profile(np.asarray(self.angles)[keep], np.asarray(self.loads)[keep],
                                length, bulk_density, self.flights, self.froude)
        out["from_sample"] = int(start)
        return out


def unloading_lines(entries) -> list[str]:
    """Markdown for a map: each (hold-up kg/m, incline deg, profile) entry's measured
    unloading curve beside the geometric model fitted in mu."""
    lines = ["", "## Flight unloading", "",
             "Each flight's load (kg per metre of drum) against its angle above the rising "
             "side's horizontal, from the samples of the steady part of the run: the mass of "
             "the touching particles between its leg, its lip's line and its tip "
             "(app/flights.py). Beside it the geometric model (the solids behind a surface "
             "through the tip at Schofield & Glikin's kinetic angle), fitted in the dynamic "
             "friction mu, the loads read as cross-sections at the bulk density given. The model "
             "is that of a flight full when it leaves the bed: at a hold-up that leaves the "
             "flights part-full its fit means nothing (a kinetic angle below 15 deg says so).",
             ""]
    for holdup, incline, p in entries:
        lines.append(f"### {holdup:.4g} kg/m, {incline:.3g} deg")
        lines.append("")
        if "fitted_friction" not in p:
            lines += ["Too few loaded samples for the model.", ""]
            continue
        part_full = p["kinetic_angle_at_0_deg"] < 15.0
        lines += [("**The flights leave the bed part-full: the fit is not meaningful.** "
                   if part_full else "") + f"Fitted mu {p['fitted_friction']:.3g} (kinetic angle "
                  f"{p['kinetic_angle_at_0_deg']:.3g} deg at 0 deg, Fr {p['froude']:.3g}); "
                  f"root-mean-square difference {100 * p['rms_difference_of_full']:.3g} % of a "
                  f"full flight's load; final discharge angle {p['final_discharge_angle_deg']:.4g}"
                  f" deg measured, {p['model_final_discharge_angle_deg']:.4g} deg modelled "
                  f"(bulk density {p['bulk_density']:.4g} kg/m^3).", "",
                  "| flight angle (deg) | load (kg/m) | model (kg/m) | samples |",
                  "|---|---|---|---|"]
        for a, m, e, mod, n in zip(p["flight_angle_deg"], p["load_kg_per_m"],
                                   p["load_standard_error"], p["model_area_m2"], p["samples"]):
            lines.append(f"| {a:.4g} | {m:.3g} +- {e:.2g} | {mod * p['bulk_density']:.3g} | {n} |")
        lines.append("")
    return lines


def plot_unloading(entries, path) -> None:
    """flights.png: each entry's measured loads (with standard errors) and its fitted model."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for holdup, incline, p in entries:
        line = ax.errorbar(p["flight_angle_deg"], p["load_kg_per_m"],
                           yerr=p["load_standard_error"], marker="o", ls="none", capsize=2,
                           label=f"{holdup:.3g} kg/m, {incline:.2g} deg")
        if "model_area_m2" in p:
            ax.plot(p["flight_angle_deg"], np.asarray(p["model_area_m2"]) * p["bulk_density"],
                    color=line[0].get_color(), label=f"model, mu {p['fitted_friction']:.2g}")
    ax.set_xlabel("flight angle above the rising side's horizontal (deg)")
    ax.set_ylabel("flight load (kg per metre of drum)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
