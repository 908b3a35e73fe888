"""Bundled demos (``taichi-dem demo NAME``): each is a scene file in demos/ and a summary that
prints its key numbers at the end of the run, against the reference it reproduces.

A demo class names its scene file, may ``attach(sim)`` observers before the run (they read the
state at every output sample) and prints ``summary(sim)`` afterwards. The geometry numbers a
summary needs (orifice, drum radius, ...) are read back from the scene's own TOML text, so an
edited scene keeps a consistent summary.

Discharge is measured from the particles that leave the domain (``particles/lost``); a scene
with a ``[[sensors]] kind = "mass_flow"`` whose name the demo gives in ``SENSOR`` is read from
``/series/sensors/<name>/mass_flow`` instead (see :func:`analysis.discharged_mass`).
"""
from __future__ import annotations

import math
import shutil
import tomllib
from pathlib import Path
from typing import Optional

import numpy as np

from . import analysis
from .. import demos as _demo_scenes
from ..scene.units import parse_quantity

# the scenes are package data of taichi_dem.demos (the checkout's demos/ folder, or the copy a
# wheel installs), so an installed taichi_dem finds them from any working directory
DEMOS_DIR = Path(_demo_scenes.__file__).resolve().parent


def _scene_toml(sim) -> dict:
    return tomllib.loads(sim.scene.text)


def _length(value) -> float:
    return parse_quantity(value, "length")


def _gravity(sim) -> float:
    return float(np.linalg.norm(sim.scene.simulation.gravity))


def first_line(path: Path) -> str:
    """What a scene file shows: its first line, a comment."""
    return path.read_text().splitlines()[0].lstrip("# ").strip() if path.exists() else ""


def tutorial_scenes() -> dict[str, Path]:
    """The tutorials' scene files (demos/tutorials/), by name (the file's stem)."""
    return {p.stem: p for p in sorted((DEMOS_DIR / "tutorials").glob("*.toml"))}


def _named_files(scene: Path) -> list[Path]:
    """The files a scene names by a relative path inside its own folder (fills, meshes), as
    paths relative to that folder."""
    home = scene.parent.resolve()
    found: list[Path] = []

    def walk(value):
        if isinstance(value, dict):
            for v in value.values():
                walk(v)
        elif isinstance(value, list):
            for v in value:
                walk(v)
        elif isinstance(value, str) and value and not Path(value).is_absolute():
            candidate = (home / value).resolve()
            if (candidate.is_file() and candidate != scene.resolve()
                    and home in candidate.parents):
                relative = candidate.relative_to(home)
                if relative not in found:
                    found.append(relative)
    walk(tomllib.loads(scene.read_text()))
    return found


def copy_scene(name: str, folder: Path) -> list[tuple[Path, Path]]:
    """Copy the scene of demo or tutorial ``name`` (KeyError: no such) into ``folder`` (made
    if missing), with the files it names inside its folder; [(source, target), ...], the
    scene first. FileExistsError (nothing copied) when a target exists."""
    scene = get(name).path if name in DEMOS else tutorial_scenes()[name]
    pairs = [(scene, folder / scene.name)] + [(scene.parent / rel, folder / rel)
                                              for rel in _named_files(scene)]
    for _, target in pairs:
        if target.exists():
            raise FileExistsError(17, "exists", str(target))
    for src, target in pairs:
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
    return pairs


class Demo:
    """One bundled demo: ``scene`` (file name in demos/), ``attach`` and ``summary``."""
    name = ""
    scene = ""

    @property
    def path(self) -> Path:
        return DEMOS_DIR / self.scene

    @property
    def description(self) -> str:
        """The first line of the scene file (a comment saying what it shows)."""
        if not self.path.exists():
            return f"(scene file {self.scene} missing)"
        return self.path.read_text().splitlines()[0].lstrip("# ").strip()

    def attach(self, sim) -> None:
        """Add observers before the run (default: none)."""

    def summary(self, sim) -> None:
        raise NotImplementedError


# ---------------------------------------------------------------------------------- pile
class Pile(Demo):
    name, scene = "pile", "pile.toml"

    def summary(self, sim):
        p = sim.particles()
        weight = float(np.sum(p["mass"][~p["fixed"]])) * _gravity(sim)
        floor = [w for w in sim.scene.walls if w.name == "floor"]
        if floor:
            fz = float(sim.series["walls/floor/force"][-1] @ np.asarray(floor[0].normal))
            print(f"summary: the floor carries {-fz:.4g} N of the pile's {weight:.4g} N weight "
                  f"({-fz / weight:.1%})")


# ---------------------------------------------------------------------------------- hopper
class Hopper(Demo):
    """Discharge of a conical hopper against Beverloo's correlation.

    The bulk density in Beverloo's law is measured: the solid fraction of the bed in the
    cylindrical bin (two diameters clear of the wall, the cone and the free surface) at every
    sample of the steady window."""
    name, scene = "hopper", "hopper.toml"
    SENSOR: Optional[str] = None        # a mass_flow sensor's name, once the scene has one

    def __init__(self):
        self.samples: list[tuple[float, float]] = []      # (time, solid fraction)

    def geometry(self, sim):
        body = _scene_toml(sim)["bodies"][0]["mesh"]
        orifice = 2 * _length(body["orifice_radius"])
        cone_top = _length(body["height"]) + _length(body.get("spout_length", 0.0))
        return orifice, _length(body["top_radius"]), cone_top

    def attach(self, sim):
        d = 2 * float(np.median(sim.placed.radius))
        _, radius, cone_top = self.geometry(sim)

        def observe(sim, values):
            p = sim.particles()
            z = p["position"][:, 2]
            if len(z) < 10:
                return
            surface = float(np.percentile(z[z > cone_top], 98)) if np.any(z > cone_top) else 0.0
            z0, z1 = cone_top + 2 * d, surface - 2 * d
            if z1 - z0 > 2 * d:
                self.samples.append((sim.time, analysis.solid_fraction_in_cylinder(
                    p, radius - 2 * d, z0, z1)))
        sim.add_observer(observe)

    def summary(self, sim):
        d = 2 * float(np.median(sim.placed.radius))
        orifice, _, _ = self.geometry(sim)
        masses = analysis.initial_masses(sim)
        rho_s = float(masses.sum() / np.sum(4.0 / 3.0 * math.pi * sim.placed.radius ** 3))
        t, out = analysis.discharged_mass(sim, self.SENSOR)
        total = float(masses.sum())
        if out[-1] < 0.6 * total:
            print(f"summary: only {out[-1] / total:.0%} of the fill discharged by t = {t[-1]:.3g} s "
                  f"(a jam, or too short a run); no steady rate to compare")
            return
        t0, t1 = analysis.steady_window(t, out, total)
        rate = analysis.linear_rate(t, out, t0, t1)
        phi = [f for (ts, f) in self.samples if t0 <= ts <= t1]
        phi = float(np.mean(phi)) if phi else 0.6
        rho_b = phi * rho_s
        w_bev = analysis.beverloo_rate(orifice, d, rho_b, _gravity(sim))
        c_fit = analysis.BEVERLOO_C * rate / w_bev
        print(f"summary: {len(masses)} spheres of d = {d * 1e3:.3g} mm through an orifice of "
              f"D = {orifice * 1e3:.3g} mm (D/d = {orifice / d:.2f})")
        print(f"  discharge rate {rate:.4g} kg/s (fit over t = {t0:.2f} - {t1:.2f} s, 15 - 60 % of "
              f"the fill out; from {'sensor ' + self.SENSOR if self.SENSOR else 'particles leaving the domain'})")
        print(f"  bulk density {rho_b:.4g} kg/m3 (solid fraction {phi:.3f} measured in the bin)")
        print(f"  Beverloo W = C rho_b sqrt(g) (D - k d)^(5/2) with C = {analysis.BEVERLOO_C}, "
              f"k = {analysis.BEVERLOO_K} (Beverloo et al. 1961; Nedderman 1992): {w_bev:.4g} kg/s")
        print(f"  simulated / Beverloo = {rate / w_bev:.3f}, i.e. C = {c_fit:.3f} "
              f"(published {analysis.BEVERLOO_C_RANGE[0]} - {analysis.BEVERLOO_C_RANGE[1]})")


# ---------------------------------------------------------------------------------- chute
class ChuteRelease(Demo):
    """Seed 004's chute with a released block: the surge's velocities and depth in the measuring section, and the
    mass flow off the chute's end.

    Frame: x down the slope, z normal to the base (gravity is tilted). At every sample the
    particles between x0 and x1 (the middle of the chute) are binned by 5 mm along x; the flow
    depth is the mean over bins of the highest sphere top; the surface velocity the mean
    down-slope velocity of the spheres within one diameter of their bin's top; the mean
    velocity that of all spheres in the section. The summary reports these at the sample
    that held the most particles in the section (the body of the surge)."""
    name, scene = "chute_release", "chute_release.toml"
    SENSOR: Optional[str] = None
    SECTION = (0.05, 0.15)             # m down the slope: the paper's developed-flow region
    BIN = 0.005

    def __init__(self):
        self.samples: list[dict] = []

    def attach(self, sim):
        def observe(sim, values):
            p = sim.particles()
            x, u = p["position"], p["velocity"]
            top = x[:, 2] + p["radius"]
            sel = (x[:, 0] >= self.SECTION[0]) & (x[:, 0] < self.SECTION[1])
            if sel.sum() < 50:
                return
            bins = ((x[sel, 0] - self.SECTION[0]) / self.BIN).astype(int)
            depth, surf_u = [], []
            for k in np.unique(bins):
                b = bins == k
                if b.sum() < 10:
                    continue
                h = top[sel][b].max()
                depth.append(h)
                near = b & (top[sel] > h - 2 * p["radius"][sel])
                surf_u.append(u[sel][near, 0].mean())
            if not depth:
                return
            self.samples.append(dict(time=sim.time, count=int(sel.sum()), depth=float(np.mean(depth)),
                                     surface=float(np.mean(surf_u)), mean=float(u[sel, 0].mean())))
        sim.add_observer(observe)

    def summary(self, sim):
        t, out = analysis.discharged_mass(sim, self.SENSOR)
        total = float(analysis.initial_masses(sim).sum())
        print(f"summary: {sim.n_initial} spheres of 1 mm released at 0.5492 m/s on a 38 deg "
              f"chute (seed 004 had a steady feed of 0.1961 kg/s, h0 = 22 mm, 34,756 particles)")
        if not self.samples:
            print("  the flow never reached the measuring section")
            return
        best = max(self.samples, key=lambda s: s["count"])
        print(f"  in x = {self.SECTION[0] * 1e3:.0f} - {self.SECTION[1] * 1e3:.0f} mm at t = "
              f"{best['time']:.3f} s ({best['count']} spheres): flow depth {best['depth'] * 1e3:.2f} mm, "
              f"surface velocity {best['surface']:.3f} m/s, mean velocity {best['mean']:.3f} m/s")
        flowing = out > 0.02 * total
        if flowing.any() and out[-1] > 0.1 * total:
            t_front = float(t[np.argmax(flowing)])
            rate = np.gradient(out, t)
            t0, t1 = analysis.steady_window(t, out, float(out[-1]), 0.1, 0.9)
            mean_rate = (0.8 * out[-1]) / max(t1 - t0, 1e-9)
            print(f"  off the chute's end: front at t = {t_front:.3f} s, peak mass flow "
                  f"{rate.max():.4g} kg/s, mean {mean_rate:.4g} kg/s while the middle 80 % of the "
                  f"discharged mass passed; {out[-1] / total:.0%} of the release out by t = {t[-1]:.3g} s")
        else:
            print(f"  {out[-1] / total:.0%} of the release left the chute by t = {t[-1]:.3g} s")


class Chute(Demo):
    """Seed 004's steady chute: a sheet inlet feeds the 38 deg chute; at steady state the flow
    depth, depth-averaged, free-surface and basal down-slope velocities at x = 30, 50, ...,
    150 mm and the mass flow leaving, beside the steady depth-averaged model for basal friction
    angles 23 and 30 deg (``summaries.chute_summary``; the measurement is
    ``analysis.chute_station``, over a slab 10 mm long centred on each station, the last one
    ending at the chute's end)."""
    name, scene = "chute", "chute.toml"
    SENSOR = "outflow"
    STATIONS = tuple(0.03 + 0.02 * k for k in range(7))   # m: 30, 50, ..., 150 mm
    HALF_SLAB = 0.005                                       # m
    START = 0.05                 # s: profiles recorded from here (the summary keeps the window)
    WINDOW = 0.1                 # s averaged at the end

    def __init__(self):
        self.samples: list = []

    def slabs(self, length: float):
        """(station, x0, x1) slabs, clipped to the chute [0, length] (m)."""
        return [(x, max(x - self.HALF_SLAB, 0.0), min(x + self.HALF_SLAB, length))
                for x in self.STATIONS]

    def attach(self, sim):
        from .summaries import chute_inlet
        width = chute_inlet(sim)["width"]
        length = float(next(x.point[0] for x in sim.scene.sensors if x.name == self.SENSOR))
        slabs = self.slabs(length)

        def observe(sim, values):
            if sim.time < self.START - 1e-9:
                return
            p = sim.particles()
            self.samples.append((sim.time, {x: analysis.chute_station(p, x0, x1, width)
                                            for x, x0, x1 in slabs}))
        sim.add_observer(observe)

    def summary(self, sim):
        from .summaries import chute_summary
        return chute_summary(sim, self.samples, self.STATIONS, self.SENSOR, self.WINDOW)


# ---------------------------------------------------------------------------------- heap
class AngleOfRepose(Demo):
    """Seed 001's fly ash: the heap left by a lifted cylinder, its flank's angle against the
    paper's 38.1 deg (measured) and 38.6 deg (its DEM)."""
    name, scene = "angle_of_repose", "angle_of_repose.toml"
    MEASURED, PAPER_DEM = 38.1, 38.6
    PAPER_DEM_SPREAD = (35.0, 43.5)       # the paper's eight DEM heaps (Table 2)

    def summary(self, sim):
        p = sim.particles()
        moving = ~p["fixed"]               # leave out the rough base
        p = {"position": p["position"][moving], "radius": p["radius"][moving]}
        tube = [b for b in sim.scene.bodies if b.name == "tube"]
        tube_bottom = (float(tube[0].vertices[:, 2].min()) + tube[0].motion.velocity[2] * sim.time
                       if tube else 0.0)
        angle, height, rings = analysis.heap_angle(p)
        ke = float(sim.series["particles/kinetic_energy"][-1])
        print(f"summary: {len(p['radius'])} fly-ash spheres of 15 mm in the domain (on a rough base of "
              f"fixed ones); heap height {height * 1e3:.0f} mm, kinetic energy {ke:.3g} J "
              f"(tube bottom at {tube_bottom:.2f} m)")
        print(f"  angle of repose {angle:.1f} deg (flank fitted over {rings} rings, 20 - 80 % of the "
              f"height) vs {self.MEASURED} deg measured and {self.PAPER_DEM} deg DEM in seed 001 "
              f"(its eight DEM heaps: {self.PAPER_DEM_SPREAD[0]} - {self.PAPER_DEM_SPREAD[1]} deg)")


# ---------------------------------------------------------------------------------- process
class Process(Demo):
    """A process scene (factories, outlets, sensors): the engineer's numbers - shaft torque and
    power, residence time, outlet temperature (and moisture), mass flows, mass balance."""

    def summary(self, sim):
        from .summaries import process_summary
        process_summary(sim)


class PaddleCooler(Process):
    name, scene = "paddle_cooler", "paddle_cooler.toml"
    FULL_LENGTH = 6.0        # m, the seed's cooler (paddle_cooler_full.toml)

    def summary(self, sim):
        """The process summary, then the seed's 6 m cooler estimated from this 0.5 m one
        (analysis.longer_cooler_outlet: this run's shell conductance per metre, plug flow)."""
        super().summary(sim)
        s = sim.series
        shell = next((b for b in sim.scene.bodies if b.name == "shell"), None)
        feed = sim.scene.factories[0] if sim.scene.factories else None
        if (shell is None or shell.temperature is None or feed is None or feed.temperature is None
                or "bodies/shell/heat_flow" not in s or len(s["time"]) < 8):
            return
        t = np.asarray(s["time"], float)
        late = t >= 0.75 * t[-1]
        words = f"mean over t = {t[late][0]:.4g} - {t[-1]:.4g} s"
        material = sim.scene.materials[feed.material]
        length = float(np.ptp(np.asarray(shell.vertices, float)[:, 0]))
        est = analysis.longer_cooler_outlet(
            np.asarray(s["bodies/shell/heat_flow"], float)[late], length,
            np.asarray(s["particles/mean_temperature"], float)[late], shell.temperature,
            feed.temperature, feed.mass_rate.at(sim.time), material.heat_capacity,
            self.FULL_LENGTH)
        print(f"summary: the seed's {self.FULL_LENGTH:g} m cooler, estimated from this "
              f"{length:.3g} m one (plug flow at this run's shell conductance per metre of "
              f"cooler {est['conductance_per_metre']:.3g} +- {est['conductance_per_metre_error']:.2g} "
              f"W/(m K), {words}; NTU {est['ntu']:.3g}): the ash would leave at "
              f"{est['outlet_temperature'] - 273.15:.1f} +- {est['outlet_temperature_error']:.1f} C "
              f"(fed at {feed.temperature - 273.15:.0f} C)")


class PaddleCoolerOptimised(Process):
    name, scene = "paddle_cooler_optimised", "paddle_cooler_optimised.toml"


class DryerDrum(Process):
    name, scene = "dryer_drum", "dryer_drum.toml"

    def summary(self, sim):
        """The process summary, then the solids and the gas along the drum beside the steady
        1-D counter-current heat balance dryer designers use (analysis.py)."""
        super().summary(sim)
        th = sim.scene.settings.get("thermal")
        gas = th.gas if th is not None else None
        if gas is None or not gas.plug_flow or not sim.scene.factories:
            return
        prof = analysis.axial_profile(sim, gas.cells, gas.axis_point, gas.axis_direction, gas.length)
        s = sim.series
        t_gas = np.asarray(s["gas/temperature"][-1], float)        # leaving each cell, along the axis
        feed = sim.scene.factories[0]
        material = sim.scene.materials[feed.material]
        solids_flow = feed.mass_rate.at(sim.time)          # kg/s of dry solids
        outlet = sim.scene.outlets[0].name if sim.scene.outlets else None
        window = s["time"] >= 0.75 * s["time"][-1]
        def mean_of(key, default):
            if key not in s:
                return default
            v = np.asarray(s[key], float)[window]
            v = v[np.isfinite(v)]
            return float(np.mean(v)) if len(v) else default
        last = np.nanmax(np.nonzero(prof["count"])[0]) if np.any(prof["count"]) else 0
        t_out = mean_of(f"outlets/{outlet}/mean_temperature", float(prof["temperature"][last]))
        x_out = mean_of(f"outlets/{outlet}/mean_moisture", float(prof.get("moisture", np.zeros(1))[last]))
        x = prof.get("moisture", np.zeros(gas.cells))
        balance = analysis.counter_current_gas_temperature(
            prof["temperature"], np.nan_to_num(x), t_out, x_out, solids_flow, gas.mass_flow,
            material.heat_capacity, gas.heat_capacity, gas.temperature, th.latent_heat,
            th.water_heat_capacity, th.evaporation_temperature)
        # the gas at a section's upstream face (it flows against the axis): leaving the cell
        # behind it, i.e. entering this one
        entering = np.append(t_gas[1:], gas.temperature) if gas.flow == "against_axis" else t_gas
        print(f"summary: along the drum at t = {sim.time:.4g} s (solids {solids_flow * 3.6:.3g} t/h, "
              f"leaving at {t_out:.4g} K, {x_out:.3g} kg/kg; gas {gas.mass_flow:g} kg/s in at "
              f"{gas.temperature:.4g} K):")
        print("  x m    particles  solids K  moisture  gas K (DEM)  gas K (1-D balance)  difference K")
        for k in range(gas.cells):
            if prof["count"][k] == 0:
                continue
            print(f"  {prof['centre'][k]:5.2f}  {prof['count'][k]:9d}  {prof['temperature'][k]:8.2f}  "
                  f"{x[k]:8.4f}  {entering[k]:11.2f}  {balance[k]:19.2f}  {entering[k] - balance[k]:12.2f}")
        print("  (the balance assumes a steady state and no heat but the gas's; the burner's "
              "radiation heats the solids near the gas inlet and makes the DEM's gas hotter than "
              "the balance there; before the bed has filled the drum the solids' profile is not "
              "steady)")
        self._against_correlations(sim, prof, entering, solids_flow)
        self._whole_dryer()

    DESIGN = "dryers/aggregate_dryer.toml"

    @staticmethod
    def _against_correlations(sim, prof, gas_entering, solids_flow):
        """This short drum's residence and gas-solids conductance per metre beside the
        correlations the march uses for a whole dryer (app/dryer.py)."""
        from .dryer import friedman_marshall_residence, perry_volumetric_coefficient
        scene = sim.scene
        gas = scene.settings.get("thermal").gas
        drum = next((b for b in scene.bodies if b.name == "drum"), None)
        if drum is None or drum.motion.speed is None:
            return
        axis = np.asarray(drum.motion.axis_direction, float)
        rel = np.asarray(drum.vertices, float) - np.asarray(drum.motion.axis_point, float)
        radius = float(np.max(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)))
        area = math.pi * radius ** 2
        gravity = np.asarray(scene.simulation.gravity, float)
        incline = math.asin(abs(gravity @ axis) / np.linalg.norm(gravity))
        rpm = abs(drum.motion.speed.at(sim.time)) * 60.0 / (2.0 * math.pi)
        particle_diameter = 2.0 * scene.factories[0].largest_radius
        fm = friedman_marshall_residence(gas.length, 2 * radius, incline, rpm, particle_diameter,
                                         gas.mass_flow / area, solids_flow / area,
                                         gas.flow == "against_axis")
        # the DEM's conductance per metre: the gas's heat over the mean gas-solids difference
        # along the cells that hold solids
        occupied = np.asarray(prof["count"]) > 0
        dx = gas.length / gas.cells
        difference = np.sum((np.asarray(gas_entering) - np.asarray(prof["temperature"]))[occupied]) * dx
        s = sim.series
        window = s["time"] >= 0.75 * s["time"][-1]
        heat = float(np.mean(np.asarray(s["gas/heat_flow"], float)[window]))
        dem = heat / difference if difference > 0 else math.nan
        perry = perry_volumetric_coefficient(gas.mass_flow / area, 2 * radius) * area
        sensor = next((x.name for x in scene.sensors if x.kind == "residence_time"), None)
        rows = sim.residence_times(sensor) if sensor else np.zeros((0, 3))
        median = float(np.median(rows[:, 2] - rows[:, 1])) if len(rows) else math.nan
        from .slice_map import BULK_SOLID_FRACTION
        bulk = BULK_SOLID_FRACTION * scene.materials[scene.factories[0].material].density
        fill = float(np.sum(sim.particles()["mass"])) / (bulk * area * gas.length)
        print(f"summary: against the flighted-drum correlations at this drum's size, speed, "
              f"incline and gas: residence {median:.3g} s (median), Friedman-Marshall's {fm:.3g} "
              f"s over its {gas.length:g} m ({median / fm:.2g}x); the gas gave the solids "
              f"{heat / 1e3:.3g} kW, {dem:.3g} W/(m K) per metre of drum (every particle in the "
              f"stream over its whole surface, the buried ones too: an upper bound) against "
              f"Perry's Ua "
              f"{perry:.3g} W/(m K) per metre ({dem / perry:.2g}x), at a fill of {fill:.2%} "
              f"(bulk {bulk:.4g} kg/m^3; the correlations were fitted at 3-8 %). This short drum shows "
              "a dryer's plumbing - flights, curtains, gas, drying - and is not a calibrated "
              "piece of one (its aggregate's rolling friction, 0.05 on single spheres, lets "
              "spheres roll freely); a whole dryer's answers come from the march below.")

    PILOT = "dryers/pilot_dryer.toml"
    DESIGN_ON_MAP = "dryers/aggregate_dryer_map.toml"

    def _whole_dryer(self):
        """The real-size dryer of demos/dryers/aggregate_dryer.toml, marched (app/dryer.py);
        then this drum as a 6 m pilot dryer on the DEM map of its own slices, beside the same
        pilot on the correlations."""
        from dataclasses import replace
        from .dryer import answer
        from .dryer_command import report, run
        d, a, spread = run(DEMOS_DIR / self.DESIGN)
        print(f"summary: the dryer this demo stands for ({self.DESIGN}, `taichi-dem dryer`), "
              "marched along its length:")
        print(report(d, a, spread, "aggregate dryer"))
        _, m, moved = run(DEMOS_DIR / self.DESIGN_ON_MAP, capacity=False)
        # each figure's change with the closures moved by the map's standard errors
        pm = {k: v or 0.0 for k, v in moved["combined"].items()}
        print(f"summary: the same dryer on the DEM map of its own drum's slices "
              f"({self.DESIGN_ON_MAP}: 18 flights, the calibrated aggregate as 24 mm spheres; "
              "+- the closures moved by the map's standard errors): "
              f"residence {m['residence_time'] / 60:.3g} +- "
              f"{pm.get('residence_time', 0.0) / 60:.2g} min (the correlations' "
              f"{a['residence_time'] / 60:.3g}), gas-solids {m['conductance_per_metre']:.3g} "
              f"W/(m K) per metre ({a['conductance_per_metre']:.3g}); the solids leave at "
              f"{m['solids_outlet_temperature'] - 273.15:.0f} C with "
              f"{m['solids_outlet_moisture']:.2%} +- {pm.get('solids_outlet_moisture', 0.0):.2%} "
              f"moisture, the gas at {m['gas_outlet_temperature'] - 273.15:.0f} +- "
              f"{pm.get('gas_outlet_temperature', 0.0):.2g} C; drive torque "
              f"{m['drive_torque'] / 1e3:.3g} kN m (the map's torque at the marched hold-up).")
        _, ms, s_moved = run(DEMOS_DIR / self.DESIGN_ON_MAP, capacity=False,
                             exposure="surface")
        spm = {k: v or 0.0 for k, v in s_moved["combined"].items()}
        print(f"summary: the same, the gas also meeting the bed's and the flights' loads' open "
              f"surface (closure.exposure = \"surface\"; an upper estimate of that part): "
              f"gas-solids {ms['conductance_per_metre']:.3g} W/(m K) per metre; the solids "
              f"leave at {ms['solids_outlet_temperature'] - 273.15:.0f} +- "
              f"{spm.get('solids_outlet_temperature', 0.0):.2g} C with "
              f"{ms['solids_outlet_moisture']:.3%} +- "
              f"{spm.get('solids_outlet_moisture', 0.0):.3%} moisture, the gas at "
              f"{ms['gas_outlet_temperature'] - 273.15:.0f} +- "
              f"{spm.get('gas_outlet_temperature', 0.0):.2g} C.")
        pilot, on_map, pilot_moved = run(DEMOS_DIR / self.PILOT, capacity=False)
        on_correlations = answer(replace(pilot, residence_time=None, conductance_per_metre=None,
                                         map_info=None, drive_torque=None))
        # the same map with the gas meeting the bed's and the flights' loads' open surface too
        _, on_surface, surface_moved = run(DEMOS_DIR / self.PILOT, capacity=False,
                                           exposure="surface")
        words = []
        # the map's figures with their change when its closures move by their standard errors
        # (the correlations' have no measured scatter)
        errors = {k: v or 0.0 for k, v in pilot_moved["combined"].items()}
        for label, x, err in (("on the DEM map of this drum's slices", on_map, errors),
                              ("the same, the gas also meeting the bed's and the loads' open "
                               "surface", on_surface,
                               {k: v or 0.0 for k, v in surface_moved["combined"].items()}),
                              ("on the correlations", on_correlations, None)):
            def pm(name, scale=1.0, fmt=".2g"):
                return f" +- {err.get(name, 0.0) * scale:{fmt}}" if err is not None else ""
            words.append(f"{label}: residence {x['residence_time'] / 60:.3g}"
                         f"{pm('residence_time', 1 / 60)} min, gas-solids "
                         f"{x['conductance_per_metre']:.3g} W/(m K) per metre, the solids leave at "
                         f"{x['solids_outlet_temperature'] - 273.15:.0f} C with "
                         f"{x['solids_outlet_moisture']:.1%} moisture, the gas at "
                         f"{x['gas_outlet_temperature'] - 273.15:.0f}"
                         f"{pm('gas_outlet_temperature')} C")
        print(f"summary: this drum as a {pilot.length:g} m pilot dryer fed "
              f"{pilot.feed * 3.6 * (1 + pilot.feed_moisture):.3g} t/h ({self.PILOT}): "
              + "; ".join(words) + ". The map's aggregate is calibrated as far as spheres go "
              "(its heap stands at 38.9 deg against angular rock's 40.5 +- 0.7; "
              "docs/calibration/aggregate): its slices convey 1.0-1.3x as fast as Friedman and "
              "Marshall's flighted drums (free-rolling spheres: 1.3-1.6x), and its curtains "
              "show the gas less surface than the correlations' dryers; the bed's and the "
              "loads' open surface doubles the exchange, still about a third of Perry's "
              "(docs/machine/dryer_slice).")


class SlotHopper(Demo):
    """Seed 000's slot hopper: fill and settle (the scene), then in the summary the settled bed
    and the discharge with [mobility] on and off (app/slot_hopper.py)."""
    name, scene = "slot_hopper", "slot_hopper.toml"

    def summary(self, sim):
        from .slot_hopper import report
        report(sim, discharge_time=0.7)


DEMOS: dict[str, type[Demo]] = {d.name: d for d in (PaddleCooler, PaddleCoolerOptimised,
                                                     DryerDrum, Pile, Hopper, Chute,
                                                     ChuteRelease, AngleOfRepose, SlotHopper)}


def get(name: str) -> Demo:
    return DEMOS[name]()
