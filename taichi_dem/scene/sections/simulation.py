"""[simulation], [domain] and [output]: their keys and how they are read."""
from __future__ import annotations

from typing import Any

from ...errors import SceneError
from ..keys import AUTO, REQUIRED, Key, Section, added_values, host_section, register
from ..keys import type_name as _type_name
from ..model import Domain, Output, SimulationSettings

# particle slots are indexed with 32-bit integers (Taichi fields)
MAX_PARTICLES = 2 ** 31 - 1
# a domain narrower than this on any axis is a unit mistake (as for meshes, geometry.mesh)
MIN_DOMAIN_SIZE = 1e-6     # m
# ... and a coordinate beyond this is one too (issue 43: a domain of +-1e29 m overflowed the
# cell count). The largest machines simulated (kilns) are ~200 m long; at 1e6 m a float32
# coordinate is resolved to 6 cm only, coarser than any particle, so no contact there could
# be computed.
MAX_COORDINATE = 1e6       # m
AXES = ("x", "y", "z")
_S = SimulationSettings

SIMULATION = register(Section("simulation", "Time, precision and the step (and the keys "
                             "effects add to it)", (
    Key("end_time", "quantity", "simulated time to run", unit="time", default=_S.end_time,
        minimum=0.0, exclusive_minimum=True),
    Key("dt", "quantity", "the time step; \"auto\": rayleigh_fraction x the Rayleigh time, "
        "bounded by the Hertz contact time", unit="time", default="auto", auto=True,
        minimum=0.0, exclusive_minimum=True),
    Key("rayleigh_fraction", "quantity", "the automatic step as a fraction of the Rayleigh time",
        unit="dimensionless", default=_S.rayleigh_fraction, minimum=0.0, maximum=1.0,
        exclusive_minimum=True, why="typically 0.1 to 0.3"),
    Key("precision", "choice", "floating-point precision of the particle state",
        default=_S.precision, choices=("f32", "f64")),
    Key("seed", "integer", "seeds numpy's generator (placement, factories)", default=_S.seed,
        minimum=0, why="it seeds numpy's generator"),
    Key("skin", "quantity", "the Verlet skin; default 0.1 x the mean diameter", unit="length",
        default=None, minimum=0.0, exclusive_minimum=True),
    Key("max_particles", "integer", "particle slots to allocate, at least the particles the "
        "fills place (default: the fills and the factories' schedules until end_time); "
        "refused when their estimated device memory exceeds the machine's",
        default=None, minimum=1, maximum=MAX_PARTICLES),
), owner=__name__))

DOMAIN = register(Section("domain", "The box particles live in (they are lost outside it) and "
                          "its periodic axes", (
    Key("min", "vector", "the lower corner", unit="length", default=REQUIRED),
    Key("max", "vector", "the upper corner", unit="length", default=REQUIRED),
    Key("periodic", "any", "periodic axes: a subset of \"x\", \"y\", \"z\"", default=(),
        schema={"type": "array", "items": {"enum": list(AXES)}, "uniqueItems": True}),
), owner=__name__))

OUTPUT = register(Section("output", "What is written and how often", (
    Key("interval", "quantity", "time between samples (series, frames); may exceed "
        "end_time (the run's end is sampled anyway), not be shorter than the time step",
        unit="time",
        default=Output.interval, minimum=0.0, exclusive_minimum=True),
    Key("frame_interval", "quantity", "time between particle frames (/frames), a whole "
        "multiple of interval; the series keep every sample (default: a frame at every sample)",
        unit="time", default=None, minimum=0.0, exclusive_minimum=True),
    Key("rrd", "string", "rerun recording (.rrd) to write, relative to the scene file's "
        "folder, which it may not leave (no absolute path, ~ or ..: name a file elsewhere with "
        "--rrd); with --out DIR its file name in DIR; an existing file that is not a rerun "
        "recording is never overwritten", default=None),
    Key("h5", "string", "HDF5 results file to write, relative to the scene file's folder, "
        "which it may not leave (no absolute path, ~ or ..: name a file elsewhere with --h5); "
        "with --out DIR its file name in DIR; an existing file that is not a taichi_dem "
        "results file is never overwritten (nor one at the checkpoint beside it)",
        default=None),
    Key("checkpoint_interval", "quantity", "simulated time between checkpoints (none when "
        "absent)", unit="time", default=None, minimum=0.0, exclusive_minimum=True),
), owner=__name__))


class SimulationSections:
    """Read by the loader's parser (scene/loader.py), which mixes this in with the reading
    helpers of common.Reader."""

    def simulation(self, value: Any) -> SimulationSettings:
        key = "simulation"
        t = self.table(value, key)
        host_section(SIMULATION).check(t, self.source, key)
        try:
            kw = host_section(SIMULATION).read(t, self.source, key, only=("dt",))
        except SceneError as e:
            raise self.err(e.key, f"{e.reason}; dt is \"auto\" or a positive time") from None
        if kw.get("dt") == AUTO:
            kw["dt"] = None
        kw.update(host_section(SIMULATION).read(t, self.source, key, only=(
            "end_time", "rayleigh_fraction", "precision", "seed", "skin")))
        kw["effect_values"] = added_values(SIMULATION.path, t, self.source, key)
        if "max_particles" in t:
            k = f"{key}.max_particles"
            kw["max_particles"] = self.integer(t["max_particles"], k)
            if kw["max_particles"] < 1:
                raise self.err(k, f"must be >= 1, got {kw['max_particles']}")
            if kw["max_particles"] > MAX_PARTICLES:
                raise self.err(k, f"{kw['max_particles']:,} is more than the "
                                  f"{MAX_PARTICLES:,} particles the engine "
                                  "can index (32-bit fields)")
        return SimulationSettings(**kw)

    def parse_domain(self, value: Any) -> Domain:
        key = "domain"
        t = self.table(value, key)
        DOMAIN.check(t, self.source, key)
        lo, hi = self.corners(t, key)
        for corner, name in ((lo, "min"), (hi, "max")):
            if max(abs(x) for x in corner) > MAX_COORDINATE:
                raise self.err(f"{key}.{name}", f"{list(corner)} lies beyond {MAX_COORDINATE:g} m "
                                                "from the origin: absurd for a DEM scene (a "
                                                "float32 coordinate there is resolved to "
                                                "centimetres; wrong units?)")
        for i, ax in enumerate(AXES):
            if hi[i] - lo[i] < MIN_DOMAIN_SIZE:
                raise self.err(f"{key}.max", f"the domain is {hi[i] - lo[i]:.3g} m across on "
                                             f"{ax}: absurd for a DEM scene (wrong units? "
                                             "lengths are in metres: write 0.2 or \"200 mm\")")
        periodic = t.get("periodic", [])
        if not isinstance(periodic, list):
            raise self.err(f"{key}.periodic", f"expected an array of axis names (\"x\", \"y\", "
                                              f"\"z\"), got {_type_name(periodic)}")
        seen: list[str] = []
        for i, a in enumerate(periodic):
            if a not in AXES:
                raise self.err(f"{key}.periodic[{i}]", f"must be \"x\", \"y\" or \"z\", got "
                                                       f"{_type_name(a)}")
            if a in seen:
                raise self.err(f"{key}.periodic[{i}]", f"axis \"{a}\" is listed twice")
            seen.append(a)
        return Domain(min=lo, max=hi, periodic=tuple(seen))

    def parse_output(self, value: Any) -> Output:
        key = "output"
        t = self.table(value, key)
        kw = OUTPUT.read(t, self.source, key)
        for k in ("rrd", "h5"):
            if k in kw and not kw[k].strip():
                raise self.err(f"{key}.{k}", "must be a non-empty file path")
        if kw.get("frame_interval") is not None:
            # frames are taken at samples: a frame interval between them would drift
            interval = kw.get("interval", Output.interval)
            ratio = kw["frame_interval"] / interval
            if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6 * ratio:
                raise self.err(f"{key}.frame_interval",
                               f"{kw['frame_interval']:g} s is not a whole multiple of "
                               f"output.interval ({interval:g} s): frames are taken at samples")
        return Output(**kw)

    def check_particle_total(self, simulation: SimulationSettings, fills, factories) -> None:
        """The fills, and the factories' schedules until end_time (unless max_particles caps
        them), must stay within what the engine can index."""
        total = 0
        for f in fills:
            total += f.expected_count
            if total > MAX_PARTICLES:
                raise self.err(f"{f.key}.count" if f.file is None else f"{f.key}.file",
                               f"the fills hold {total:,} particles, more than the "
                               f"{MAX_PARTICLES:,} the engine can index (32-bit fields)")
        if simulation.max_particles is not None:
            if simulation.max_particles < total:
                # the engine sizes its slots from max_particles: fewer slots than the fills
                # place was silently ignored before (issue 43)
                raise self.err("simulation.max_particles",
                               f"{simulation.max_particles:,} particle slots are fewer than the "
                               f"{total:,} particles the fills place; raise max_particles to "
                               f"at least {total:,} (or leave it out)")
            return
        expected = float(total)
        for f in factories:
            mass = f.mass_rate.mass_until(simulation.end_time)
            expected += mass / (self.materials[f.material].density * f.mean_particle_volume())
            if not 1.1 * expected + 64 <= MAX_PARTICLES:
                raise self.err(f"{f.key}.mass_rate",
                               f"the schedules insert about {expected:.3g} particles by "
                               f"end_time = {simulation.end_time:g} s, more than the "
                               f"{MAX_PARTICLES:,} the engine can index; lower the rate, "
                               "shorten end_time or cap them with [simulation] max_particles")
