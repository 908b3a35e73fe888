"""Factories: continuous insertion at a scheduled mass rate (host side, numpy).

Every ``interval`` a factory inserts the particles that bring its inserted mass to the
scheduled mass (the integral of the rate), rounded to whole particles, so the inserted mass
never drifts from the schedule by more than one particle plus what the region could not take.
Particles are placed at random in the region without overlap: clear of the particles already
there, of walls and of body triangles at their current pose. When the region is full the rest
waits for the next insertion and the run says so once per episode - never a silent shortfall;
``/series/factories/<name>/behind`` is the mass behind schedule (kg).

``pattern = "sheet"`` factories (an inlet that keeps up with a chute's feed, hundreds of
thousands of particles per second) insert whole lattice layers through their face instead
(:class:`~taichi_dem.scene.model.SheetInlet`): layer j, of mass M_j, is due at the time t_j
the schedule reaches the mass before it plus half its own, C_j + M_j / 2, and goes in at the
first whole step t >= t_j, already u_n (t - t_j) in front of its sites - where it would be had
it gone in at t_j - so successive layers are u_n (M_{j-1} + M_j) / (2 mass_rate) apart along
the normal and the stream carries exactly the scheduled mass (to half a layer). Layers are
built with numpy (no per-particle Python); a site that overlaps a particle still there (a
stream that backs up), a wall or a body is dropped, counted behind schedule and warned about.

The particles go into free slots of the engine (``Engine.insert``); each gets a slot key not in
use (``particle_id``, re-used after its particle is gone) and a run-wide ``serial`` id, its
factory index and its birth time (for the residence time).
"""
from __future__ import annotations

import math
import sys
import time as time_module

import numpy as np

from taichi_dem.geometry.mesh import rotation_matrix
from ..setup.placement import (_Grid, _Triangles, _conflicts, _frame, _local_bounds, _valid,
                               sample_radii)

# automatic interval: the time the particles need to clear their own diameter, within
# [MIN_INTERVAL_STEPS steps, MAX_INTERVAL]; one batch is then at most 0.5 % of a second's feed
MIN_INTERVAL_STEPS = 20
MAX_INTERVAL = 0.005            # s
CANDIDATES_PER_PARTICLE = 6     # random trial positions per particle wanted, per attempt
ATTEMPTS = 3


class FactorySet:
    """The scene's factories and their progress. ``sim``: the Simulation (engine, tables)."""

    def __init__(self, sim, first_serial: int):
        self.sim = sim
        scene = sim.scene
        self.scene = scene
        self.factories = scene.factories
        self.rng = np.random.default_rng([scene.simulation.seed, 7919])
        self.next_serial = first_serial
        n = len(self.factories)
        self.inserted_mass = np.zeros(n)          # kg
        self.inserted_energy = 0.0                # J, sum m c T of every particle inserted
        self.inserted_count = np.zeros(n, np.int64)
        self.behind = np.zeros(n)                 # kg behind schedule after the last insertion
        self.waiting = [False] * n                # in a "region full" episode (warned)
        self.capacity_warned = False
        self.wall_seconds = 0.0                   # spent placing and inserting (host)
        self.next_radius = [self._sample_radius(k) for k in range(n)]
        dt = sim.dt
        g = float(np.linalg.norm(scene.simulation.gravity))
        self.every = []                           # steps between insertions (None: sheet)
        # sheet factories: layers done, mass of the layers done (kg), lattice sites per parity
        self.layers = np.zeros(n, np.int64)
        self.layer_mass_before = np.zeros(n)
        self.sheet_sites: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for k, f in enumerate(self.factories):
            if f.pattern == "sheet":
                sh = f.sheet
                e_w = np.asarray(sh.width, float) / sh.extents[0]
                e_d = np.asarray(sh.depth, float) / sh.extents[1]
                front = np.asarray(sh.normal, float) * (sh.radius + sh.jitter_amplitude)
                self.sheet_sites[k] = tuple(
                    np.asarray(sh.point, float) + front + st[:, :1] * e_w + st[:, 1:] * e_d
                    for st in (sh.sites(0), sh.sites(1)))
                self.every.append(None)
                continue
            if f.interval is not None:
                interval = f.interval
            else:
                v = float(np.linalg.norm(f.velocity))
                d = 2.0 * f.largest_radius
                # time to move one diameter from the insertion speed under gravity
                t_clear = (d / v if g == 0 else (-v + math.sqrt(v * v + 2.0 * g * d)) / g) if (v or g) else 0.0
                interval = min(max(t_clear, MIN_INTERVAL_STEPS * dt), MAX_INTERVAL)
            wanted = max(1, int(round(interval / dt)))
            # a whole number of insertions per output interval, so every sample sees the
            # inserted mass on schedule (to half a particle)
            out = sim.output_every
            self.every.append(max(1, out // max(1, -(-out // wanted))) if wanted < out else wanted)
        names = sim.tables.names
        self.material = [names.index(f.material) for f in self.factories]
        self.density = [scene.materials[f.material].density for f in self.factories]
        self.names = names
        self.npf = np.float64 if sim.precision == "f64" else np.float32
        self.gravity = np.asarray(scene.simulation.gravity, float)
        # the step the current run of steps ends at when factories are due there (else None):
        # what insert_at_rebuild may insert early (Simulation.step sets it)
        self.window_end = None
        self._triangle_cache: dict = {}           # _candidate_triangles, per body and box

    # ------------------------------------------------------------------ radii
    def _sample_radius(self, k: int) -> float:
        f = self.factories[k]
        if f.sizes:
            r = np.array([s[0] for s in f.sizes])
            # mass fraction f_k of size r_k means a number fraction ~ f_k / r_k^3
            p = np.array([s[1] for s in f.sizes]) / r ** 3
            return float(r[self.rng.choice(len(r), p=p / p.sum())])
        return float(sample_radii(f.radius, 1, self.rng)[0])

    def particle_mass(self, k: int, radius: float) -> float:
        """Mass of a sphere of factory k as the device stores it (rounded to its precision)."""
        return float(self.npf(4.0 / 3.0 * math.pi * radius ** 3 * self.density[k]))

    # ------------------------------------------------------------------ stepping
    def steps_to_next(self, step: int) -> int:
        """Steps from ``step`` to the next insertion of any factory (>= 1)."""
        nxt = [e - (step % e) for e in self.every if e is not None]
        nxt += [max(1, self._sheet_step(k) - step) for k in self.sheet_sites
                if math.isfinite(self._layer_time(k))]
        return min(nxt) if nxt else 1 << 62

    def due(self, step: int) -> list[int]:
        return [k for k, e in enumerate(self.every)
                if (step % e == 0 if e is not None else self._sheet_step(k) <= step)]

    # ------------------------------------------------------------------ sheets
    def layer_mass(self, k: int, j: int) -> float:
        """Mass (kg) of layer ``j`` of sheet factory ``k`` (parity j % 2)."""
        return len(self.sheet_sites[k][j % 2]) * self.particle_mass(k, self.factories[k].sheet.radius)

    def _layer_time(self, k: int) -> float:
        """When the next layer of sheet factory k is due (s): the schedule has reached the mass
        of the layers before it plus half its own."""
        j = int(self.layers[k])
        return self.factories[k].mass_rate.time_for_mass(
            self.layer_mass_before[k] + 0.5 * self.layer_mass(k, j))

    def _sheet_step(self, k: int) -> int:
        """The first whole step at or after the next layer's due time (huge if never)."""
        t = self._layer_time(k)
        if not math.isfinite(t):
            return 1 << 62
        return int(math.ceil(t / self.sim.dt - 1e-9))

    def insert_due(self, step: int, time: float):
        """Insert for every factory due at ``step`` (state at a whole step, time s)."""
        # a factory served at a neighbour rebuild before this step (insert_at_rebuild) has
        # nothing left to insert unless part of its batch found no room
        due = [k for k in self.due(step) if self.every[k] is None or self._has_due(k, time)]
        if not due:
            return
        t0 = time_module.perf_counter()
        try:
            self._insert(due, time)
        finally:
            self.wall_seconds += time_module.perf_counter() - t0

    def _has_due(self, k: int, time: float) -> bool:
        """Whether factory k (not a sheet) has a whole particle due by ``time`` (s); else its
        behind-schedule mass is brought up to date."""
        target = self.factories[k].mass_rate.mass_until(time)
        m = self.particle_mass(k, self.next_radius[k])
        if self.inserted_mass[k] + 0.5 * m > target:
            self.behind[k] = max(target - self.inserted_mass[k], 0.0)
            return False
        return True

    def insert_at_rebuild(self, engine):
        """The engine's hook before a neighbour rebuild within a run of steps: insert now what
        the factories due at the run's last step (``window_end``, set by Simulation.step) would
        insert then, so that one rebuild serves both; a rebuild costs several steps of a small
        scene, and insertions alone forced one every ~40 steps in the main demo (half of its
        rebuilds). The batch is the scheduled mass at the due time, so at most one run early
        (an insertion interval, <= MAX_INTERVAL) and never across an output sample (a run ends
        at each). The state is mid-step (drifted, forces pending): a new particle gets
        v0 - g dt/2, which the coming half kick of its free flight brings to v0. Sheet
        factories keep their exact layer spacing and insert at their due steps only."""
        end = self.window_end
        if end is None:
            return
        due_time = end * self.sim.dt
        due = [k for k in self.due(end) if self.every[k] is not None]
        due = [k for k in due if self._has_due(k, due_time)]
        if not due:
            return
        t0 = time_module.perf_counter()
        try:
            self._insert(due, engine.time, schedule_time=due_time, mid_step=True)
        finally:
            self.wall_seconds += time_module.perf_counter() - t0

    def _insert(self, due: list[int], time: float, schedule_time: "float | None" = None,
                mid_step: bool = False):
        """Insert the batches of factories ``due`` at ``time`` (s), with the scheduled mass
        at ``schedule_time`` (default ``time``); ``mid_step``: the engine is between its drift
        and its forces (insert_at_rebuild)."""
        engine = self.sim.engine
        n = engine.count
        # what is in the simulation now (the placement avoids it)
        now = engine.occupied()
        alive = now["alive"]
        pos = now["position"][alive]
        rad = now["radius"][alive]
        keys_in_use = now["particle_id"]
        batches = []
        for k in due:
            if self.factories[k].pattern == "sheet":
                new = []
                while self._sheet_step(k) * self.sim.dt <= time + 0.5 * self.sim.dt:
                    batch = self._sheet_layer(k, time, pos, rad)
                    if batch is not None:
                        new.append(batch)
                        pos = np.concatenate([pos, batch["position"]])
                        rad = np.concatenate([rad, batch["radius"]])
                batches.extend(new)
                continue
            batch = self._batch(k, time, pos, rad, time if schedule_time is None else schedule_time)
            if batch is not None:
                batches.append(batch)
                pos = np.concatenate([pos, batch["position"]])
                rad = np.concatenate([rad, batch["radius"]])
        if not batches:
            return
        arrays = {key: np.concatenate([b[key] for b in batches]) for key in batches[0]}
        if mid_step:
            # velocities at t - dt/2 like every other particle's: the half kick of free flight
            # that follows brings them to the factory's velocity at t
            arrays["velocity"] = arrays["velocity"] - 0.5 * self.sim.dt * self.gravity
        m = len(arrays["radius"])
        free = engine.model.particle_limit - n
        if m > free:
            if not self.capacity_warned:
                self.capacity_warned = True
                print(f"taichi-dem: warning: at t = {time:.4g} s the particle capacity "
                      f"({engine.model.particle_limit}) is reached; factories wait. Raise "
                      f"[simulation] max_particles.", file=sys.stderr)
            # give back what does not fit (its mass stays behind schedule)
            for k in due:
                sel = arrays["origin"][free:] == k
                self.inserted_mass[k] -= float(np.sum(arrays["mass"][free:][sel]))
                self.inserted_count[k] -= int(np.sum(sel))
                self.behind[k] = max(self.factories[k].mass_rate.mass_until(time)
                                     - self.inserted_mass[k], 0.0)
            for key in arrays:
                arrays[key] = arrays[key][:free]
            m = free
            if m == 0:
                return
        used = np.zeros(engine.state.capacity, bool)
        used[keys_in_use] = True
        arrays["key"] = np.nonzero(~used)[0][:m].astype(np.int32)
        arrays["serial"] = np.arange(self.next_serial, self.next_serial + m, dtype=np.int64)
        self.next_serial += m
        arrays["birth_time"] = np.full(m, time)
        if "inverse_thermal_mass" in arrays:
            # m c T brought in (J), for the energy balance (thermal/energy_balance.py)
            self.inserted_energy += float(np.sum(arrays["temperature"] / arrays["inverse_thermal_mass"]))
        engine.insert(arrays)

    def _batch(self, k: int, time: float, pos: np.ndarray, rad: np.ndarray,
               schedule_time: float):
        """Factory k's particles due by ``schedule_time`` (s), placed at ``time`` (s) clear of
        ``pos``/``rad``; None if none."""
        f = self.factories[k]
        target = f.mass_rate.mass_until(schedule_time)
        radii, masses = [], []
        planned = self.inserted_mass[k]
        # whole particles up to the scheduled mass (a particle goes in once half of it is due)
        while True:
            r = self.next_radius[k]
            m = self.particle_mass(k, r)
            if planned + 0.5 * m > target:
                break
            radii.append(r)
            masses.append(m)
            planned += m
            self.next_radius[k] = self._sample_radius(k)
        if not radii:
            self.behind[k] = max(target - self.inserted_mass[k], 0.0)
            return None
        radii = np.array(radii)
        placed_pos, ok = self._place(f, radii, time, pos, rad)
        # the radii that did not fit wait (their order is kept: the next batch starts with them)
        waiting = radii[~ok]
        if len(waiting):
            self.next_radius[k] = float(waiting[0])
            # (the later unplaced radii are re-sampled; the distribution is unchanged)
        radii, masses = radii[ok], np.array(masses)[ok]
        placed_pos = placed_pos[ok]
        self.inserted_mass[k] += float(np.sum(masses))
        self.inserted_count[k] += len(radii)
        self.behind[k] = max(target - self.inserted_mass[k], 0.0)
        if len(waiting) and not self.waiting[k]:
            self.waiting[k] = True
            print(f"taichi-dem: warning: at t = {time:.4g} s factory '{f.name}' could place only "
                  f"{len(radii)} of {len(radii) + len(waiting)} particles: its region is full. "
                  f"Insertion waits ({self.behind[k]:.4g} kg behind schedule); enlarge the region "
                  f"or check that the material leaves it.", file=sys.stderr)
        elif not len(waiting) and self.waiting[k]:
            self.waiting[k] = False
            print(f"taichi-dem: at t = {time:.4g} s factory '{f.name}' inserts again "
                  f"({self.behind[k]:.4g} kg behind schedule)", file=sys.stderr)
        if not len(radii):
            return None
        return self._arrays(k, placed_pos, radii, masses)

    def _sheet_layer(self, k: int, time: float, pos: np.ndarray, rad: np.ndarray):
        """The next layer of sheet factory k at ``time`` (s), clear of ``pos``/``rad``."""
        f = self.factories[k]
        sh = f.sheet
        j = int(self.layers[k])
        t_due = self._layer_time(k)
        m_one = self.particle_mass(k, sh.radius)
        sites = self.sheet_sites[k][j % 2]
        v = np.asarray(f.velocity, float)
        # where the layer would be had it gone in at its due time (spacing exact, no drift)
        shift = v * max(time - t_due, 0.0)
        # jitter: uniform in the ball of radius jitter_amplitude
        n = len(sites)
        d = self.rng.normal(size=(n, 3))
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
        d *= sh.jitter_amplitude * self.rng.uniform(size=(n, 1)) ** (1.0 / 3.0)
        x = sites + shift + d
        r = np.full(n, sh.radius)
        ok = self._clear(x, r, time, pos, rad)
        scheduled = len(sites) * m_one
        self.layers[k] += 1
        self.layer_mass_before[k] += scheduled
        x, r = x[ok], r[ok]
        masses = np.full(len(r), m_one)
        self.inserted_mass[k] += float(np.sum(masses))
        self.inserted_count[k] += len(r)
        self.behind[k] = max(self.layer_mass_before[k] - self.inserted_mass[k], 0.0)
        dropped = n - len(r)
        # warned once per run (a stream near its limit drops a sphere now and then; the total
        # is /series/factories/<name>/behind)
        if dropped and not self.waiting[k]:
            self.waiting[k] = True
            print(f"taichi-dem: warning: at t = {time:.4g} s sheet factory '{f.name}' dropped "
                  f"{dropped} of {n} spheres of a layer: they would overlap particles still in "
                  f"front of the face (the stream backs up), a wall or a body "
                  f"({self.behind[k]:.4g} kg behind schedule); check that the material leaves "
                  f"the face, or lower mass_rate. Further drops are not reported: see "
                  f"/series/factories/{f.name}/behind.", file=sys.stderr)
        if not len(r):
            return None
        return self._arrays(k, x, r, masses)

    def _clear(self, x: np.ndarray, r: np.ndarray, time: float, pos: np.ndarray,
               rad: np.ndarray) -> np.ndarray:
        """Mask of spheres (x, r) inside the domain, clear of plane walls, of body triangles at
        their pose at ``time`` and of the spheres ``pos``/``rad`` (vectorised)."""
        scene = self.scene
        dlo, dhi = np.asarray(scene.domain.min, float), np.asarray(scene.domain.max, float)
        ok = np.all((x - r[:, None] >= dlo) & (x + r[:, None] <= dhi), axis=1)
        for w in scene.walls:
            ok &= (x - np.asarray(w.point)) @ np.asarray(w.normal) >= r
        r_max = float(r.max())
        reach = r_max + (float(rad.max()) if len(rad) else 0.0)
        lo, hi = x.min(axis=0) - reach, x.max(axis=0) + reach
        tris = self._triangles(time, lo, hi, r_max)
        if tris is not None and len(tris.tri) and ok.any():
            idx = np.nonzero(ok)[0]
            ok[idx[tris.hits(x[idx], r[idx])]] = False
        if len(pos) and ok.any():
            per = [ax in scene.domain.periodic for ax in "xyz"]
            near = np.all((pos >= lo) & (pos <= hi), axis=1)
            if per and any(per):
                near[:] = True                 # images across a periodic face may reach
            if near.any():
                npos, nrad = pos[near], rad[near]
                grid = _Grid(npos, 2.0 * max(r_max, float(nrad.max())), dlo, dhi, per)
                idx = np.nonzero(ok)[0]
                ok[idx[_conflicts(grid, nrad, x[idx], r[idx])]] = False
        return ok

    def _arrays(self, k: int, placed_pos: np.ndarray, radii: np.ndarray, masses: np.ndarray) -> dict:
        """The engine's insert arrays for particles of factory k."""
        f = self.factories[k]
        n = len(radii)
        out = {"position": placed_pos, "velocity": np.tile(np.asarray(f.velocity, float), (n, 1)),
               "radius": radii, "mass": masses,
               "material": np.full(n, self.material[k], np.int32),
               "origin": np.full(n, k, np.int32)}
        # what the enabled effects give them (Effect.source_values: the temperature, moisture
        # and thermal mass with heat)
        for effect in self.sim.engine.model.effect_list:
            out.update(effect.source_values(self.scene, f, self.names, out["material"], masses))
        return out

    def _place(self, f, radii: np.ndarray, time: float, pos: np.ndarray, rad: np.ndarray):
        """Random positions in the factory region, clear of ``pos``/``rad`` spheres, walls,
        body triangles at ``time`` and each other. Returns (positions, placed mask)."""
        scene = self.scene
        region = f.region
        origin, axes = _frame(region)
        lo, hi = _local_bounds(region)
        r_max = float(radii.max())
        # only what is near the region matters
        wlo, whi = self._world_bounds(region, r_max + (float(rad.max()) if len(rad) else 0.0))
        near = np.all((pos >= wlo) & (pos <= whi), axis=1) if len(pos) else np.zeros(0, bool)
        npos, nrad = pos[near], rad[near]
        dlo, dhi = np.asarray(scene.domain.min), np.asarray(scene.domain.max)
        per = [ax in scene.domain.periodic for ax in "xyz"]
        tris = self._triangles(time, wlo, whi, r_max)
        out = np.zeros((len(radii), 3))
        ok = np.zeros(len(radii), bool)
        accepted_pos: list[np.ndarray] = []
        accepted_r: list[float] = []
        for _ in range(ATTEMPTS):
            todo = np.nonzero(~ok)[0]
            if len(todo) == 0:
                break
            m = CANDIDATES_PER_PARTICLE * len(todo) + 16
            # centres where the largest sphere still to place lies wholly inside the region
            room = float(radii[todo].max())
            local = (lo + room) + (hi - lo - 2.0 * room) * self.rng.uniform(size=(m, 3))
            if region.kind == "cylinder":
                # uniform in the disk: radius ~ sqrt(u)
                rho = (region.radius - room) * np.sqrt(self.rng.uniform(size=m))
                phi = self.rng.uniform(0.0, 2.0 * math.pi, m)
                local[:, 1], local[:, 2] = rho * np.cos(phi), rho * np.sin(phi)
            cand = origin + local @ axes
            # each candidate is tried for the largest radius still to place (conservative)
            rr = np.full(m, room)
            grid = _Grid(npos, 2.0 * max(r_max, float(nrad.max()) if len(nrad) else r_max),
                         dlo, dhi, per) if len(npos) else None
            valid = _valid(scene, region, cand, rr, grid, nrad, tris)
            cand = cand[valid]
            for c in cand:
                if len(todo) == 0:
                    break
                i = todo[0]
                if accepted_pos:
                    ap = np.asarray(accepted_pos)
                    d2 = np.sum((ap - c) ** 2, axis=1)
                    if np.any(d2 < (np.asarray(accepted_r) + radii[i]) ** 2 * (1.0 + 1e-9)):
                        continue
                out[i] = c
                ok[i] = True
                accepted_pos.append(c)
                accepted_r.append(radii[i])
                todo = todo[1:]
        return out, ok

    def _world_bounds(self, region, pad: float):
        from ..scene.loader import region_bounds
        lo, hi = region_bounds(region)
        return lo - pad, hi + pad

    def _triangles(self, time: float, lo, hi, r_max: float):
        """Body triangles near [lo, hi] (within ``r_max``, m) at their pose at ``time`` (None
        without bodies). Called at every insertion: the triangles of each body that can come
        near the box at all are found once per box (by their extent along the body's axis,
        which its rotation keeps), and only those are moved."""
        if not self.scene.bodies:
            return None
        kin = self.sim.engine.kinematics
        lo_pad = np.asarray(lo, float) - r_max
        hi_pad = np.asarray(hi, float) + r_max
        moved = []
        for k, b in enumerate(self.scene.bodies):
            m = b.motion
            tri = self._candidate_triangles(k, lo_pad, hi_pad)
            angle = kin.angle(k, time)
            shift = np.asarray(m.velocity, float) * time
            if angle != 0.0:
                rot = rotation_matrix(np.asarray(m.axis_direction, float), angle)
                p = np.asarray(m.axis_point, float)
                tri = (tri - p) @ rot.T + p
            if np.any(shift):
                tri = tri + shift
            keep = np.all((tri.max(axis=1) >= lo_pad) & (tri.min(axis=1) <= hi_pad), axis=1)
            if keep.any():
                moved.append(tri[keep])
        if not moved and not self.scene.domain.periodic:
            return None                 # (a periodic image might still come near)
        return _Triangles(self.scene, 2.0 * r_max,
                          triangles=np.concatenate(moved) if moved else np.empty((0, 3, 3)))

    def _candidate_triangles(self, k: int, lo, hi) -> np.ndarray:
        """(T, 3, 3) m: body k's triangles at t = 0 that can come within the box [lo, hi] at
        some pose: all of them for a translating body, else those whose span along the axis
        meets the box's (cached per box)."""
        key = (k, tuple(lo), tuple(hi))
        cached = self._triangle_cache.get(key)
        if cached is not None:
            return cached
        b = self.scene.bodies[k]
        tri = np.asarray(b.vertices, float)[np.asarray(b.faces, np.int64).reshape(-1, 3)]
        m = b.motion
        if not np.any(np.asarray(m.velocity, float)) and len(tri):
            u = np.asarray(m.axis_direction, float)
            p = np.asarray(m.axis_point, float)
            along = (tri - p) @ u                                    # (T, 3)
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                for z in (lo[2], hi[2])])
            box = (corners - p) @ u
            tri = tri[(along.max(axis=1) >= box.min()) & (along.min(axis=1) <= box.max())]
        if len(self._triangle_cache) > 64:
            self._triangle_cache.clear()
        self._triangle_cache[key] = tri
        return tri

    # ------------------------------------------------------------------ series
    def sample(self, values: dict, now):
        """/series factories/<name>/mass (kg inserted), count and behind (kg behind schedule)."""
        for k, f in enumerate(self.factories):
            values[f"factories/{f.name}/mass"] = self.inserted_mass[k]
            values[f"factories/{f.name}/count"] = float(self.inserted_count[k])
            values[f"factories/{f.name}/behind"] = self.behind[k]

    def state_dict(self) -> dict:
        return {"inserted_mass": self.inserted_mass.copy(), "inserted_count": self.inserted_count.copy(),
                "behind": self.behind.copy(), "waiting": np.array(self.waiting, bool),
                "next_radius": np.array(self.next_radius), "next_serial": self.next_serial,
                "layers": self.layers.copy(), "layer_mass_before": self.layer_mass_before.copy(),
                "inserted_energy": self.inserted_energy,
                "rng": str(self.rng.bit_generator.state)}

    def load_state_dict(self, d: dict):
        import ast
        self.inserted_mass = np.asarray(d["inserted_mass"], float).copy()
        self.inserted_count = np.asarray(d["inserted_count"], np.int64).copy()
        self.behind = np.asarray(d["behind"], float).copy()
        self.waiting = [bool(x) for x in d["waiting"]]
        self.next_radius = [float(x) for x in d["next_radius"]]
        self.next_serial = int(d["next_serial"])
        if "layers" in d:                      # (checkpoints from before sheet factories lack them)
            self.layers = np.asarray(d["layers"], np.int64).copy()
            self.layer_mass_before = np.asarray(d["layer_mass_before"], float).copy()
        self.inserted_energy = float(d.get("inserted_energy", 0.0))
        self.rng.bit_generator.state = ast.literal_eval(str(d["rng"]))
