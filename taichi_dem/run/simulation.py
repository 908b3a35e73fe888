"""The user's handle on one simulation: build from a scene, step, observe, record.

    sim = Simulation.from_toml("scene.toml", arch="cpu")
    sim.run(until=1.0)
    sim.series["particles/kinetic_energy"]

Several simulations can live in one process (they share the Taichi runtime; see backend.py)
as long as they use the same arch and precision; ``close()`` frees a simulation's fields.
"""
from __future__ import annotations

import functools
import math
import os
import sys
import time as _time
from typing import Optional

import numpy as np

from ..contacts.law import margin_fraction
from ..effects import enabled_effects
from ..effects.base import Effect
from ..engine import backend, transfer
from . import interrupt
from ..setup.tuning import MOST_SPECIES
from ..errors import DivergenceError, SceneError, StaleSimulationError
from ..scene import catalog
from ..scene.loader import load_scene, parse_scene
from ..scene.model import Scene
from ..sensors import Now, build_sensors
from ..sensors.particles import mass_inside
from ..sensors.pooling import amounts, pool, should_pool
from ..setup.pair_tables import build_pair_tables
from ..setup.memory import factory_capacity as _factory_capacity
from ..setup.placement import place_fills
from ..setup.timestep import choose_step_and_skin


def _sizes_to_expect(scene: Scene, placed, names):
    """Radii, material indices, speeds and fixed flags of the initial particles plus the
    smallest and largest particle each factory inserts (for dt, skin and cell size)."""
    radii = [placed.radius]
    mats = [placed.material]
    speeds = [np.linalg.norm(placed.velocity, axis=1)]
    fixed = [placed.fixed]
    for f in scene.factories:
        r = np.array([f.smallest_radius, f.largest_radius])
        radii.append(r)
        mats.append(np.full(2, names.index(f.material), np.int32))
        speeds.append(np.full(2, float(np.linalg.norm(f.velocity))))
        fixed.append(np.zeros(2, bool))
    return (np.concatenate(radii), np.concatenate(mats).astype(np.int32),
            np.concatenate(speeds), np.concatenate(fixed))


def _particle_species(scene: Scene, placed, names, most: int = MOST_SPECIES):
    """The species of particle the scene holds or inserts: ((material index, radius m), ...)
    sorted, or None when there are more than ``most`` or a factory samples its radii from a
    distribution (engine tables per species: the gas gap's)."""
    species = set()
    if len(placed.radius):
        rows = np.unique(np.column_stack([np.asarray(placed.material, np.float64),
                                          np.asarray(placed.radius, np.float64)]), axis=0)
        if len(rows) > most:
            return None
        species.update((int(m), float(r)) for m, r in rows)
    for f in scene.factories:
        if f.sizes:
            radii = [r for r, _ in f.sizes]
        elif f.radius is not None:
            if f.radius.std != 0.0:
                return None
            radii = [f.radius.mean]
        else:
            radii = [f.sheet.radius]
        species.update((names.index(f.material), float(r)) for r in radii)
    if len(species) > most:
        return None
    return tuple(sorted(species))


def _check_periodic_axes(scene: Scene, max_radius: float, effects=None) -> None:
    """Refuse a periodic axis too short for one image of each partner to be the only one in
    reach: its length must exceed two interaction reaches, 2 (2 r_max + lens), the contact
    distance plus the gas gap's lens where pairs conduct through it.

    The Verlet skin is not limited by the period: a pair stands once in the lists (the search
    visits a wrapped cell once on an axis of one or two cells), its separation is the minimum
    image at every step, and that distance changes by no more than the two partners' drift, so
    a list built at a cutoff of reach + skin holds every pair within reach until a particle
    has drifted half the skin. (Until 2026-12-07 the skin was shrunk below L/2 - reach, and a
    quasi-2D slab of 2.5 diameters rebuilt its lists every 5 steps.)"""
    span = np.asarray(scene.domain.max, float) - np.asarray(scene.domain.min, float)
    contact = 2.0 * max_radius
    # pairs within a contact margin are listed too (the gas gap near contacts): the effect
    # that asks for the widest names its key
    if effects is None:
        effects = enabled_effects(scene)
    margin = margin_fraction(effects, "pair") * max_radius
    widest = max((e for e in effects if e.stage == "contact" and "pair" in e.kinds),
                 key=lambda e: e.margin, default=None)
    for k, axis in enumerate("xyz"):
        if axis not in scene.domain.periodic:
            continue
        length = float(span[k])
        if length <= 2.0 * contact:
            raise SceneError(scene.source, "domain.periodic",
                             f"the periodic length along {axis} ({length:.4g} m) must exceed two "
                             f"contact distances, 2 x 2 r_max = {2.0 * contact:.4g} m (r_max = "
                             f"{max_radius:.4g} m): a particle would touch two images of one "
                             f"partner; enlarge the domain along {axis}")
        if margin > 0.0 and length <= 2.0 * (contact + margin):
            key = widest.margin_key or "domain.periodic"
            advice = f"{widest.margin_advice}, or " if widest.margin_advice else ""
            raise SceneError(scene.source, key,
                             f"{widest.name} reaches {margin:.4g} m beyond contact, and the "
                             f"periodic length along {axis} ({length:.4g} m) must exceed two "
                             f"pair reaches 2 (2 r_max + {margin:.4g} m) = "
                             f"{2.0 * (contact + margin):.4g} m; {advice}enlarge the domain")


# overlap (fraction of the radius) with a body beyond which particles are reported as pinched
PINCH_WARNING = 0.2


# progress lines into a log (stderr not a terminal): one every this many wall seconds (the
# environment variable TAICHI_DEM_PROGRESS_S overrides it)
PLAIN_PROGRESS_S = 10.0
# the ETA's simulated-time rate is taken over this much recent wall time
ETA_WINDOW_S = 20.0


def eta_seconds(remaining: float, wall_per_particle_second: float, count: float,
                count_rate: float, limit: float, horizon: float = math.inf) -> float:
    """Wall seconds left for ``remaining`` s of simulated time (issue 48 item 3): the recent
    cost of one particle for one simulated second (wall s per particle per simulated s) times
    the particle-seconds still to come. The count grows at its recent ``count_rate``
    (particles per simulated s: a machine filling from its factories) for ``horizon`` more
    simulated seconds at most, and never past ``limit`` (the slots the scene may fill), then
    stays; it never falls below today's. A filling machine's cost grows with its hold-up, which
    an ETA from the recent simulated-time rate alone missed (1.75x too optimistic while the
    cooler filled); growing to the end of the run instead overshot 15x in its first seconds,
    as outlets balance the feed long before the slots are full."""
    if not remaining > 0:
        return 0.0
    rate = max(count_rate, 0.0)
    grows = min(remaining, max(horizon, 0.0), (limit - count) / rate if rate > 0 else 0.0)
    grows = max(grows, 0.0)
    top = count + rate * grows
    particle_seconds = count * grows + 0.5 * rate * grows ** 2 + top * (remaining - grows)
    return wall_per_particle_second * particle_seconds


def engine_parts(scene: Scene):
    """What the engine takes from the layers above it for ``scene`` (engine/stepper.py
    EngineParts): the bodies' kinematics and mesh contacts, the process device."""
    from ..engine.stepper import EngineParts
    from ..process.outlets import ProcessDevice
    kinematics = mesh = None
    if scene.bodies:
        from ..bodies.kinematics import BodyKinematics
        from ..bodies.mesh_contacts import MeshContacts
        kinematics, mesh = BodyKinematics(scene.bodies), MeshContacts
    return EngineParts(kinematics=kinematics, mesh=mesh, process=ProcessDevice)


class Simulation:
    """One DEM simulation. Units SI throughout (m, kg, s, K, N)."""

    def __init__(self, scene: Scene, *, arch: str = "cpu", precision: Optional[str] = None,
                 threads: Optional[int] = None, h5: Optional[str] = None,
                 parallel_from: Optional[int] = None):
        """``parallel_from``: particles from which a CPU runs the step's loops on all
        threads (below it: one thread, several steps per launch; engine/stepper.py
        PARALLEL_FROM; 0: always parallel)."""
        from ..engine.model import Model
        from ..engine.stepper import Engine

        self.scene = scene
        self.arch = arch
        self.precision = precision or scene.simulation.precision
        self._stale: Optional[str] = None
        self._generation = backend.acquire(self, arch, self.precision, threads)
        self.real = backend.real_type(self.precision)

        rng = np.random.default_rng(scene.simulation.seed)
        placed = place_fills(scene, rng)
        self.placed = placed
        self.n_initial = len(placed.radius)
        if self.n_initial == 0 and not scene.factories:
            raise SceneError(scene.source, "particles", "the scene has no particles (no fill "
                                                        "and no factory)")
        self.tables = build_pair_tables(scene)
        # placement numbers materials in sorted order too; make sure of it
        assert list(placed.materials) == self.tables.names or not placed.materials
        # the time step and cells must suit the particles factories will insert, too
        radii, materials, speeds, fixed = _sizes_to_expect(scene, placed, self.tables.names)
        self.timestep, self.skin = choose_step_and_skin(scene, radii, materials,
                                                        self.tables.names, speeds, fixed)
        # the enabled effects, built once (effects/registry.py)
        self._effects = enabled_effects(scene)
        _check_periodic_axes(scene, float(np.max(radii)), effects=self._effects)
        self.dt = self.timestep.dt
        capacity = self.n_initial + _factory_capacity(scene)

        model = Model.build(scene, self.tables, self.real, self.dt, self.skin,
                            float(np.max(radii)), max(capacity, 1),
                            species=_particle_species(scene, placed, self.tables.names),
                            effects=self._effects)
        self.engine = Engine(model, parallel_from=parallel_from, parts=engine_parts(scene))
        reach = (2.0 + self.engine.model.pair_margin) * float(np.max(radii))
        small = self.engine.model.grid.too_small_periodic_axes(reach)
        if small:     # (_check_periodic_axes makes this unreachable; kept as a guard)
            self.engine.destroy()
            raise SceneError(scene.source, "domain.periodic",
                             f"the periodic length along {', '.join(small)} is shorter than two "
                             f"interaction reaches ({2 * reach:.4g} m)")
        self._upload(placed)
        self._warn_biot()
        self.engine.start(self.n_initial)
        self.step_count = 0
        self.time = 0.0
        self._last_sample_time = 0.0
        # the last sample's interval and its interval series' amounts (sensors/pooling.py)
        self._interval_tail = None
        self.output_every = max(1, int(round(scene.output.interval / self.dt)))
        # the simulated time from which the next sample writes a particle frame ([output]
        # frame_interval; every sample without it)
        self._next_frame_time = 0.0
        self.factories = None
        self.accounts = None
        if scene.factories:
            from ..process.factories import FactorySet
            self.factories = FactorySet(self, first_serial=self.n_initial)
            # a batch due at the end of a run of steps goes in at a rebuild within it
            self.engine.before_rebuild = self.factories.insert_at_rebuild
        if scene.factories or scene.outlets or scene.sensors:
            from ..process.accounting import ProcessAccounts
            self.accounts = ProcessAccounts(self)
        # what turns the state into /series values at each sample, by name, in the order
        # their series are written (sensors/; the outlet accounts and factories among them)
        self.sensors: dict = build_sensors(self)
        # host-side parts whose state a checkpoint must keep: name -> object with
        # state_dict() / load_state_dict(d)
        self.checkpointables: dict = {k: v for k, v in (
            ("factories", self.factories), ("accounts", self.accounts),
            ("residence", self.sensors.get("residence")),
            ("energy", self.sensors.get("energy"))) if v is not None}
        self._series: dict[str, list] = {}
        self.recorder = None
        if h5 is None:      # the scene's [output] h5: inside its folder (consistency.py)
            from ..scene.sections.consistency import resolve_output_path
            h5 = resolve_output_path(scene.source, "output.h5", scene.output.h5)
        if h5:
            from ..recorders.hdf5 import HDF5Recorder
            self.recorder = HDF5Recorder(h5, scene_text=scene.text, dt=self.dt, arch=arch,
                                         precision=self.precision)
            self.recorder.write_bodies(scene.bodies, self.tables.names)
        self.wall_seconds = 0.0
        # What runs at every output sample besides the sensors, in order (_sample): ``checks``,
        # check(measured) before anything is taken from the state (may raise DivergenceError);
        # ``observers``, observe(sim, values) with the sample's /series values (recorders,
        # scripts; they never change the state); ``after_sample``, hook(sim) once the sample
        # is recorded. ``on_divergence``: handler(sim, err) -> err when a step diverged.
        self.checks: list = []
        self.observers: list = []
        self.after_sample: list = []
        self.on_divergence: list = []
        self._attach_run_observers()
        self._sample()

    def _attach_run_observers(self):
        """The observers every simulation runs with: the divergence guard (run/divergence.py)
        and the checkpoint writer (periodic checkpoints, the last good state for a divergence;
        run/checkpoint.py). Imported here, not at module top: they are observers of the run,
        and checkpoint.py builds simulations when it resumes one."""
        from .checkpoint import Checkpointer
        from .divergence import DivergenceGuard
        self.divergence = DivergenceGuard(self)
        self.checkpointer = Checkpointer(self)
        self.checks += [self.divergence, self._check_state]
        # the stability checks the enabled effects contribute (effects/base.py: Effect.check)
        for effect in self.engine.model.effect_list:
            if type(effect).check is not Effect.check:
                self.checks.append(functools.partial(effect.check, self))
        self.after_sample.append(self.checkpointer.after_sample)
        self.on_divergence.append(self.checkpointer.diverged)

    # ---------------------------------------------------------------- construction
    @classmethod
    def from_toml(cls, path: str, **kwargs) -> "Simulation":
        """Load and validate a scene file (SceneError on bad input) and build it."""
        return cls(load_scene(path), **kwargs)

    @classmethod
    def from_text(cls, text: str, *, base_dir: Optional[str] = None, source: str = "<string>",
                  **kwargs) -> "Simulation":
        return cls(parse_scene(text, source=source, base_dir=base_dir), **kwargs)

    @classmethod
    def from_checkpoint(cls, path: str, **kwargs) -> "Simulation":
        """Continue from a checkpoint file (checkpoint.resume: arch, threads, h5, checkpoint,
        configure)."""
        from .checkpoint import resume
        return resume(path, build=cls, **kwargs)

    def _upload(self, placed):
        """The initial fill into the engine, by the same insertion as the factories'
        (engine/insertion.py)."""
        n = self.n_initial
        density = self.tables.density[placed.material]
        mass = 4.0 / 3.0 * math.pi * placed.radius ** 3 * density
        arrays = {"position": placed.position, "velocity": placed.velocity,
                  "angular_velocity": placed.angular_velocity, "fixed": placed.fixed,
                  "radius": placed.radius, "mass": mass, "material": placed.material,
                  "key": np.arange(n), "serial": np.arange(n), "origin": np.full(n, -1),
                  "birth_time": np.zeros(n)}
        # what the enabled effects give each fill's particles (Effect.source_values: the
        # temperature, moisture and thermal mass with heat)
        for effect in self.engine.model.effect_list:
            for i, fill in enumerate(self.scene.fills):
                sel = placed.fill == i
                given = effect.source_values(self.scene, fill, self.tables.names,
                                             placed.material[sel], mass[sel])
                for name, values in given.items():
                    arrays.setdefault(name, np.zeros(len(mass)))[sel] = values
        self.engine.insert(arrays)

    def _mark_stale(self, why: str):
        self._stale = why

    def _check_alive(self):
        if self._stale:
            raise StaleSimulationError(f"this simulation can no longer be used: {self._stale}")
        if self.engine is None:
            raise StaleSimulationError("this simulation was closed")

    # ---------------------------------------------------------------- advancing
    def step(self, n: int = 1):
        """Advance ``n`` time steps, sampling series (and frames) at output intervals."""
        self._check_alive()
        t0 = _time.perf_counter()
        remaining = int(n)
        try:
            while remaining > 0:
                to_output = self.output_every - (self.step_count % self.output_every)
                chunk = min(remaining, to_output)
                if self.factories is not None:
                    chunk = min(chunk, self.factories.steps_to_next(self.step_count))
                    end = self.step_count + chunk
                    self.factories.window_end = end if self.factories.due(end) else None
                self.engine.advance(chunk, record_last=(chunk == to_output))
                if self.factories is not None:
                    self.factories.window_end = None
                self.step_count += chunk
                self.time = self.step_count * self.dt
                remaining -= chunk
                if self.factories is not None:
                    # before the sample, so a sample sees the mass inserted on schedule
                    self.factories.insert_due(self.step_count, self.time)
                if self.step_count % self.output_every == 0:
                    self._sample()
                interrupt.check()            # Ctrl-C on the command line lands here
        except DivergenceError as err:
            # the checkpoint writer writes the last good state and names it in the message
            for handle in self.on_divergence:
                err = handle(self, err)
            raise err from None
        self.wall_seconds += _time.perf_counter() - t0

    def run(self, until: Optional[float] = None, *, progress: bool = False):
        """Advance to simulated time ``until`` (s; default the scene's end_time)."""
        until = self.scene.simulation.end_time if until is None else float(until)
        steps = int(round((until - self.time) / self.dt))
        if not progress:
            self.step(max(steps, 0))
            return
        # progress on stderr: on a terminal one line rewritten twice a second, else (a log
        # file) a plain line every PLAIN_PROGRESS_S; the rate counts the particle-steps done
        # (the count changes as factories feed and outlets remove), the ETA comes from the
        # simulated-time rate over the last ETA_WINDOW_S of wall time (not from the start,
        # whose compilation would inflate it)
        tty = sys.stderr.isatty()
        every = 0.5 if tty else float(os.environ.get("TAICHI_DEM_PROGRESS_S", PLAIN_PROGRESS_S))
        done = 0
        particle_steps = 0.0
        t0 = _time.perf_counter()
        block = max(self.output_every, 1)
        shown = -1.0
        recent = [(0.0, self.time, 0.0, float(self.engine.count))]
        try:
            while done < steps:
                k = min(block, steps - done)
                self.step(k)
                done += k
                particle_steps += k * self.engine.count
                wall = _time.perf_counter() - t0
                recent.append((wall, self.time, particle_steps * self.dt, float(self.engine.count)))
                while len(recent) > 2 and wall - recent[1][0] > ETA_WINDOW_S:
                    recent.pop(0)
                if wall - shown < every and done < steps:
                    continue
                shown = wall
                rate = particle_steps / wall if wall > 0 else 0.0
                # the ETA from the recent cost per particle and simulated second, and the
                # count's recent growth (eta_seconds)
                (w0, s0, ps0, n0) = recent[0]
                cost = ((wall - w0) / (particle_steps * self.dt - ps0)
                        if particle_steps * self.dt > ps0 else float("nan"))
                growth = ((self.engine.count - n0) / (self.time - s0) if self.time > s0
                          else 0.0)
                # (the count keeps growing for as long again as it has been simulated: a
                # machine fills in a time of the order of its run so far)
                eta = eta_seconds(until - self.time, cost, float(self.engine.count), growth,
                                  float(self.engine.model.particle_limit), horizon=self.time)
                line = (f"  t = {self.time:8.4f} s   wall {wall:7.1f} s   "
                        f"{rate / 1e6:6.2f} M particle-steps/s   ETA {eta:6.1f} s")
                if tty:
                    print("\r" + line, end="", file=sys.stderr, flush=True)
                else:
                    print(line, file=sys.stderr, flush=True)
        finally:
            # (also when interrupted: the next message starts on a line of its own)
            if tty and shown >= 0:
                print(file=sys.stderr, flush=True)
            self.progress_particle_steps = particle_steps

    def sample_now(self) -> bool:
        """Take an output sample at the current time unless the last one was taken here (True
        when it took one). Samples fall every ``output_every`` steps; a run that stops between
        two (``end_time`` not a whole number of sample steps: 70 s at dt 1.2e-4 s and a 0.5 s
        interval ends 4,166 steps after its last regular sample) closes with this one, so its
        series, frames and summary describe the same instant as the final state. Its interval
        is the shorter time since the previous sample (the sensors' rates use it)."""
        self._check_alive()
        if self.time <= self._last_sample_time + 0.5 * self.dt:
            return False
        self._sample(frame=True)
        return True

    def body_poses(self, time: Optional[float] = None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """{body name: (R, T)} at ``time`` (s; default now): a vertex the scene gives at x0 is at
        R x0 + T (R 3x3, T in m)."""
        kin = getattr(self.engine, "kinematics", None)
        t = self.time if time is None else float(time)
        if kin is None:
            return {}
        return {b.name: kin.pose(k, t) for k, b in enumerate(self.scene.bodies)}

    def _frame_due(self) -> bool:
        """Whether this sample writes a particle frame: every sample, or with [output]
        frame_interval F the first sample at or after each multiple of F (samples fall every
        output_every steps, so within half a sample interval of it)."""
        every = self.scene.output.frame_interval
        if every is None:
            return True
        slack = 0.5 * self.output_every * self.dt
        if self.time < self._next_frame_time - slack:
            return False
        self._next_frame_time = (math.floor((self.time + slack) / every) + 1) * every
        return True

    # ---------------------------------------------------------------- observing
    def _sample(self, frame: bool = False):
        """One output sample: the checks, then each sensor adds its /series values, then the
        series are stored, the observers see them, the results file gets them (with a frame
        and the residence records completed since the last sample), and the after-sample
        hooks run (the checkpoint writer)."""
        m = self.engine.measure()
        for check in self.checks:       # NaN, overlap, speed (divergence.py); _check_state
            check(m)
        interval = self.time - self._last_sample_time
        nominal = self.output_every * self.dt
        # a short interval (the run stops between two regular samples) is pooled with the one
        # before it: no sample's rates stand for less than a full interval (sensors/pooling.py)
        pooling = should_pool(interval, nominal, self.dt, self._interval_tail)
        covered = interval + (self._interval_tail["interval"] if pooling else 0.0)
        now = Now(time=self.time, interval=interval, measured=m,
                  pooled_interval=covered - interval)
        values = {"time": self.time, "sample_interval": covered}
        if self.scene.settings.get("thermal") is not None and self.scene.settings.get("thermal").time_scale != 1.0:
            # the time the heat has had: S x simulated time ([thermal] time_scale)
            values["thermal_time"] = self.scene.settings.get("thermal").time_scale * self.time
        for sensor in self.sensors.values():
            sensor.sample(values, now)
        if pooling:
            tail = pool(values, interval, self._interval_tail["amounts"], nominal)
        else:
            tail = amounts(values, interval)
        # what a next short sample pools with (kept in checkpoints: run/checkpoint.py)
        self._interval_tail = {"interval": covered, "amounts": tail} if covered > 0.0 else None
        self._last_sample_time = self.time
        for name, v in values.items():
            self._series.setdefault(name, []).append(np.asarray(v, dtype=np.float64))
        for observe in self.observers:
            observe(self, values)
        residence = self.sensors["residence"].pop_new() if "residence" in self.sensors else {}
        if self.recorder is not None:
            self.recorder.append_series(values)
            for name, rec in residence.items():
                self.recorder.append_residence(name, rec)
            if self._frame_due() or frame:
                arrays = self.particles()
                self.recorder.append_frame(self.time, {k: arrays[k] for k in (
                    "id", "position", "velocity", "angular_velocity", "radius", "mass", "material",
                    "temperature", "moisture")
                    if k in arrays}, poses=self.body_poses())
            self.recorder.flush()
        for hook in self.after_sample:          # the periodic checkpoint, the last good state
            hook(self)

    def _check_state(self, measured: dict):
        """The checks of the sample's measurements (after the divergence guard): a state the
        sums found non-finite (a velocity, a temperature not above 0 K) stops the run with the
        quantity named (divergence.py), a thermal step past its limit too; contacts resolved
        in too few steps and pinched particles are warned about once."""
        if measured["non_finite"]:
            raise DivergenceError(self.divergence.non_finite_message(self.time, None, measured))
        self._check_contact_resolution(measured["max_speed"])
        if self.engine.mesh is not None:
            self._check_pinching(self.engine.mesh.survey.deepest_overlaps(self.engine.count))

    def _check_pinching(self, deepest: np.ndarray):
        """Say once per body when particles are pinched against it: an overlap beyond
        PINCH_WARNING of the radius means a gap narrower than the particles (paddle tips and
        the shell) squeezes them; the run goes on - stable, the kinematic body wins - but the
        forces there are not those of real particles, which would break or block the drive."""
        warned = self.__dict__.setdefault("_warned_pinch", set())
        for k, body in enumerate(self.scene.bodies):
            if deepest[k] > PINCH_WARNING and body.name not in warned:
                warned.add(body.name)
                print(f"taichi-dem: warning: at t = {self.time:.4g} s particles are pinched "
                      f"against '{body.name}': overlap {deepest[k]:.0%} of the radius (beyond "
                      f"{PINCH_WARNING:.0%}). A gap narrower than the particles (a paddle-tip "
                      f"clearance?) squeezes them; the run stays stable but the loads there are "
                      f"not physical. Widen the gap or use smaller particles.", file=sys.stderr)

    def _warn_biot(self):
        """A particle is one temperature (lumped) only while its Biot number h (r/3) / k_p is
        small; warn above 0.1 (at the gas velocity, particles at rest)."""
        th = self.scene.settings.get("thermal")
        if th is None or th.gas is None:
            return
        gas = th.gas
        worst = 0.0
        for k, name in enumerate(self.tables.names):
            sel = self.placed.material == k
            if not np.any(sel):
                continue
            r = float(np.max(self.placed.radius[sel]))
            re = gas.density * 2 * r * float(np.linalg.norm(gas.velocity)) / gas.viscosity
            pr = gas.heat_capacity * gas.viscosity / gas.conductivity
            nu = 2 + 0.6 * math.sqrt(re) * pr ** (1 / 3)
            biot = gas.conductivity * nu / (2 * r) * (r / 3) / self.scene.materials[name].thermal_conductivity
            worst = max(worst, biot)
        if worst > 0.1:
            print(f"taichi-dem: warning: Biot number {worst:.2g} > 0.1: the particles' insides are "
                  f"not at one temperature, and the lumped model overestimates their heating rate",
                  file=sys.stderr)

    def thermal_energy(self) -> float:
        """sum m c T over the particles, J (thermal scenes)."""
        return self.engine.measure()["thermal_energy"]

    def _check_contact_resolution(self, max_speed: float):
        """The Hertz contact time shrinks as v^(-1/5): warn once if the fastest particle now
        present would be resolved in too few steps by the current dt."""
        from ..setup.timestep import ERROR_STEPS_PER_CONTACT
        ts = self.timestep
        if getattr(self, "_warned_speed", False) or max_speed <= ts.expected_speed:
            return
        contact_time = ts.contact_time * (ts.expected_speed / max_speed) ** 0.2
        if self.dt > contact_time / ERROR_STEPS_PER_CONTACT:
            self._warned_speed = True
            print(f"taichi-dem: warning: at t = {self.time:.4g} s a particle moves at "
                  f"{max_speed:.3g} m/s, faster than the {ts.expected_speed:.3g} m/s the time "
                  f"step was chosen for; its impacts last {contact_time:.3g} s, fewer than "
                  f"{ERROR_STEPS_PER_CONTACT} steps of {self.dt:.3g} s. Reduce simulation.dt.",
                  file=sys.stderr)

    def set_speed(self, body: str, speed) -> None:
        """From now on, turn ``body`` at ``speed`` (rad/s, or a quantity string such as
        "20 rpm") about its axis. Warns when the new speed is too fast for the time step."""
        from ..scene.units import parse_quantity
        from ..setup.timestep import BODY_STEP_ERROR
        self._check_alive()
        names = [b.name for b in self.scene.bodies]
        if body not in names:
            raise SceneError("set_speed", body, f"no body named '{body}'; bodies: {', '.join(names) or 'none'}")
        value = parse_quantity(speed, "angular_speed", file="set_speed", key=body)
        k = names.index(body)
        kin = self.engine.kinematics
        kin.set_speed(k, self.time, value)
        self.engine.mesh.upload_schedules()
        r_min = float(np.min(self.placed.radius))
        if kin.surface_speed(k, self.time) * self.dt > BODY_STEP_ERROR * r_min:
            print(f"taichi-dem: warning: at {value:.3g} rad/s the surface of '{body}' moves "
                  f"{kin.surface_speed(k, self.time) * self.dt / r_min:.2f} of the smallest radius "
                  f"per step; thin parts may pass through particles. Reduce dt.", file=sys.stderr)

    @property
    def series(self) -> dict[str, np.ndarray]:
        """Sampled time series, numpy arrays under the names of /series (CONTRACT.md)."""
        return {k: np.array(v) for k, v in self._series.items()}

    def particles(self) -> dict[str, np.ndarray]:
        """Alive particles in id order: id, position (m), velocity (m/s), angular_velocity
        (rad/s), radius (m), mass (kg), fixed (bool), material (index into the scene's sorted
        material names, ``sim.tables.names``); and the per-particle fields the enabled effects
        add to a frame (scene/catalog.py frame_fields: temperature K, moisture kg/kg)."""
        self._check_alive()
        s = self.engine.state
        n = self.engine.count
        names = ["alive", "serial" if s.process else "particle_id", "position", "velocity",
                 "angular_velocity", "radius", "mass", "inverse_mass", "material"]
        # the effects' per-particle fields (the temperature, the moisture) and their f64
        # residuals in f32 scenes (engine/precision.py), where the particles carry them
        model = self.engine.model
        extra = [name for name in catalog.frame_fields() if model.carries(name)]
        names += [n for name in extra
                  for n in (name, name + "_residual") if model.carries(n)]
        if self.engine.model.split_positions:
            names.append("position_residual")
        host = dict(zip(names, transfer.read(getattr(s, name) for name in names)))
        alive = np.nonzero(host["alive"][:n] != 0)[0]
        ids = host[names[1]][alive]
        order = alive[np.argsort(ids, kind="stable")]
        out = {"id": np.sort(ids, kind="stable")}
        for name in ("position", "velocity", "angular_velocity", "radius", "mass"):
            out[name] = host[name][:n][order].astype(np.float64)
        if "position_residual" in host:
            out["position"] += host["position_residual"][:n][order]
        out["fixed"] = host["inverse_mass"][:n][order] == 0.0
        out["material"] = host["material"][:n][order].astype(np.int32)
        for name in extra:
            if name in host:
                out[name] = host[name][:n][order].astype(np.float64)
                if name + "_residual" in host:
                    out[name] += host[name + "_residual"][:n][order]
        return out

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy of the moving particles, J."""
        self._check_alive()
        return self.engine.measure()["kinetic_energy"]

    @property
    def particle_count(self) -> int:
        """Particles in the simulation now."""
        return self.engine.alive_count

    def mass_inside(self) -> float:
        """Mass of the particles in the simulation now, kg (float64 sum of the stored masses)."""
        return mass_inside(self.engine)

    def mass_balance(self) -> dict:
        """initial + fed = inside + removed + lost, kg; ``error`` is the difference."""
        if self.accounts is not None:
            self.accounts.collect()              # take what the removal log holds now
        initial = float(np.sum((4.0 / 3.0 * math.pi * self.placed.radius ** 3
                                * self.tables.density[self.placed.material]).astype(
            np.float64 if self.precision == "f64" else np.float32).astype(np.float64)))
        fed = float(np.sum(self.factories.inserted_mass)) if self.factories else 0.0
        removed = float(np.sum(self.accounts.outlet_mass)) if self.accounts else 0.0
        lost = self.accounts.lost_mass if self.accounts else math.nan
        inside = self.mass_inside()
        return {"initial": initial, "fed": fed, "inside": inside, "removed": removed,
                "lost": lost, "error": initial + fed - inside - removed - lost}

    def residence_times(self, sensor: str) -> np.ndarray:
        """(id, t_in s, t_out s) rows of the particles that completed the path of residence
        sensor ``sensor`` so far."""
        return self.sensors["residence"].records(sensor)

    @property
    def effects(self):
        """The enabled effects, in step order (effects/registry.py)."""
        return self.engine.model.effect_list

    def add_observer(self, observe, *, now: bool = True):
        """Call ``observe(sim, values)`` at every output sample (and at once if ``now``) with
        the sample's /series values. Observers read the state; they must not change it."""
        self.observers.append(observe)
        if now:
            observe(self, {k: v[-1] for k, v in self._series.items()})

    def close(self):
        """Free device memory and close the recorder."""
        for observe in self.observers:
            if hasattr(observe, "close"):
                observe.close()
        self.observers = []
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None
        if getattr(self, "engine", None) is not None and not self._stale:
            self.engine.destroy()
        self.engine = None
        backend.release(self)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
