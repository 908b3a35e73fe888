from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent

SMALL_SCENE = """
[simulation]
end_time = 0.02
gravity = [0.0, 0.0, -9.81]
precision = "{precision}"
seed = 3

[domain]
min = [-0.05, -0.05, -0.01]
max = [0.05, 0.05, 0.2]

[[walls]]
name = "floor"
plane = {{ point = [0, 0, 0], normal = [0, 0, 1] }}
material = "steel"

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5
rolling_friction = {rolling}

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5
rolling_friction = {rolling}

[[particles]]
material = "glass"
radius = 0.004
count = {count}
region = {{ box = {{ min = [-0.04, -0.04, 0.005], max = [0.04, 0.04, 0.1] }} }}

[output]
interval = 0.005
"""


# a steel paddle turning about x (from rest, then 6 rpm from t = 0.05 s) and one glass bead on it
PLATE_SCENE = """
[simulation]
end_time = 1.0
gravity = [0.0, 0.0, -9.81]
precision = "f64"

[domain]
min = [-0.1, -0.1, -0.1]
max = [0.1, 0.1, 0.1]

[materials.glass]
density = 2500.0
youngs_modulus = 1e7
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["glass", "glass"]
restitution = 0.5
friction = 0.5

[[interactions]]
pair = ["glass", "steel"]
restitution = 0.5
friction = 0.5

[[bodies]]
name = "paddle"
material = "steel"
mesh = { builder = "box", min = [-0.02, -0.01, -0.005], max = [0.02, 0.06, 0.0], normals = "outward" }
motion = { rotate = { axis_point = [0, 0, 0], axis_direction = [1, 0, 0], speed = [[0.0, "0 rpm"], [0.05, "6 rpm"]] } }

[[particles]]
material = "glass"
radius = 0.004
count = 1
region = { box = { min = [-0.01, 0.03, 0.001], max = [0.01, 0.05, 0.02] } }

[output]
interval = 0.01
"""


@pytest.fixture
def small_scene_text():
    def make(precision="f64", rolling=0.05, count=200):
        return SMALL_SCENE.format(precision=precision, rolling=rolling, count=count)
    return make


def listed_pairs(sim) -> tuple[list, list]:
    """The neighbour lists as (owner id, partner id) pairs: those of the owned entries, and
    those of the partner entries (each pair should stand once in each)."""
    e = sim.engine
    s = e.state
    n = e.count
    start, owned = s.row_start.to_numpy()[:n], s.row_owned.to_numpy()[:n]
    count = s.row_count.to_numpy()[:n]
    ids = s.particle_id.to_numpy()[:n]
    nb = e.pairs.neighbour.to_numpy()
    own = [(int(ids[i]), int(ids[nb[k]])) for i in range(n) for k in range(start[i], start[i] + owned[i])]
    partner = [(int(ids[nb[k]]), int(ids[i])) for i in range(n)
               for k in range(start[i] + owned[i], start[i] + count[i])]
    return own, partner


def pairs_within(sim, cutoff_extra: float) -> set:
    """Brute force: (smaller id, larger id) of the pairs closer than r_i + r_j +
    ``cutoff_extra`` (m), by the minimum image on the periodic axes."""
    e = sim.engine
    s = e.state
    n = e.count
    x = s.position.to_numpy()[:n].astype(float)
    r = s.radius.to_numpy()[:n].astype(float)
    ids = s.particle_id.to_numpy()[:n]
    d = x[:, None, :] - x[None, :, :]
    for k in range(3):
        if e.model.grid.periodic[k]:
            d[..., k] -= e.model.grid.span[k] * np.round(d[..., k] / e.model.grid.span[k])
    close = np.linalg.norm(d, axis=2) < r[:, None] + r[None, :] + cutoff_extra
    i, j = np.nonzero(close & (ids[:, None] < ids[None, :]))
    return {(int(ids[a]), int(ids[b])) for a, b in zip(i, j)}


# ------------------------------------------------------------------ scheduling (tasks.py test)
# The suite runs on two pytest-xdist workers, each test file on one worker (--dist loadfile,
# so module fixtures run once). Two things keep both cores busy to the end:
#
# 1. Files go out slowest first (longest-processing-time order, --no-loadscope-reorder in
#    tasks.py keeps this order): a long file handed out last would leave the other worker
#    idle for its whole duration. SLOW_FILES lists the files that take over ~15 s (seconds
#    measured on a two-core machine in a two-worker run, cold kernel cache, with
#    TAICHI_DEM_SUITE_PROFILE, 2026-12-06: `python bench/suite_profile.py`; the drum wall heat,
#    packed and heated beds from `--durations` after their cuts of 2026-12-07); the rest keep
#    their collection order after them. Only the order of the files changes, never a test.
# 2. Tests marked ``two_cores`` (the engine's own worker threads: two threads meeting at spin
#    barriers) run while the other pytest worker waits between its tests: a barrier whose
#    partner thread has lost its core spins until the OS preempts it, which made those tests
#    ten times slower with another process on the second core. The gate: a ``two_cores``
#    test takes an exclusive lock, every other test a shared one (both through a gate lock,
#    so that a waiting exclusive request is served before new shared ones).
SLOW_FILES = {
    "tests/verification/test_drum_wall_heat.py": 125,
    "tests/verification/test_packed_bed.py": 100,
    "tests/verification/test_coarse_grained_wall.py": 82,
    "tests/verification/test_saeman_drum.py": 74,
    "tests/unit/test_loop_mode.py": 69,
    "tests/verification/test_heated_bed.py": 28,
    "tests/unit/test_slice_map.py": 57,
    "tests/unit/test_checkpoint.py": 44,
    "tests/unit/test_compile_once.py": 44,
    "tests/unit/test_sweep_runs.py": 43,
    "tests/verification/test_process.py": 42,
    "tests/verification/test_direct_check.py": 41,
    "tests/unit/test_engine_surface.py": 41,
    "tests/regression/test_cooler.py": 39,
    "tests/verification/test_thermal_gas.py": 38,
    "tests/regression/test_hard_cases.py": 36,
    "tests/verification/test_gas_gap_pair.py": 36,
    "tests/regression/test_angle_of_repose.py": 34,
    "tests/unit/test_mobility.py": 32,
    "tests/regression/test_hopper_beverloo.py": 32,
    "tests/verification/test_gas_gap_table.py": 30,
    "tests/regression/test_slot_hopper_mobility.py": 30,
    "tests/verification/test_mesh_contacts.py": 29,
    "tests/verification/test_thermal.py": 29,
    "tests/verification/test_resume.py": 28,
    "tests/verification/test_gas_gap_wall.py": 27,
    "tests/verification/test_flight_unloading.py": 27,
    "tests/stability/test_periodic_slices.py": 26,
    "tests/verification/test_drum.py": 24,
    "tests/unit/test_checkpoint_cli.py": 24,
    "tests/verification/test_sheet_inlet.py": 21,
    "tests/unit/test_plots.py": 21,
    "tests/verification/test_drag.py": 20,
    "tests/unit/test_neighbour_search.py": 19,
    "tests/regression/test_drum_torque.py": 19,
    "tests/verification/test_chung_ooi.py": 19,
    "tests/unit/test_calibrate.py": 19,
    "tests/fuzz/test_bad_files.py": 19,
    "tests/verification/test_screw.py": 17,
    "tests/verification/test_dryer_march.py": 16,
    "tests/verification/test_energy_balance.py": 16,
    "tests/verification/test_first_layer.py": 16,
}


# Before them: the file with the ``two_cores`` tests, those tests first, on one worker while
# the other starts on the fuzz corpus (hundreds of tests of milliseconds each), so that the
# exclusive hold waits milliseconds for the other worker's test in progress, not minutes.
FIRST_FILES = ["tests/unit/test_loop_mode.py", "tests/fuzz/test_fuzz_scenes.py"]


def pytest_collection_modifyitems(session, config, items):
    """The files in the order above; within a file the tests keep their order but for the
    ``two_cores`` ones, which go first."""
    def rank(item):
        path = item.nodeid.split("::", 1)[0]
        first = FIRST_FILES.index(path) if path in FIRST_FILES else len(FIRST_FILES)
        return first, -SLOW_FILES.get(path, 0), item.get_closest_marker("two_cores") is None
    items.sort(key=rank)            # (a stable sort: the rest keep their order)


class _CoreGate:
    """Shared (most tests) or exclusive (``two_cores`` tests) hold on the cores, across the
    pytest-xdist workers of one run (flock on files named by the run's id)."""

    def __init__(self, run_id: str):
        import tempfile
        base = Path(tempfile.gettempdir()) / f"taichi-dem-cores-{run_id}"
        self.gate = open(f"{base}.gate", "a+")
        self.hold = open(f"{base}.hold", "a+")

    def acquire(self, exclusive: bool) -> None:
        import fcntl
        fcntl.flock(self.gate, fcntl.LOCK_EX)
        try:
            fcntl.flock(self.hold, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        finally:
            if not exclusive:
                fcntl.flock(self.gate, fcntl.LOCK_UN)

    def release(self, exclusive: bool) -> None:
        import fcntl
        fcntl.flock(self.hold, fcntl.LOCK_UN)
        if exclusive:
            fcntl.flock(self.gate, fcntl.LOCK_UN)


_gate: list = []


def _core_gate():
    import os
    run_id = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if not run_id or os.name != "posix":
        return None                 # one process: nothing to share the cores with
    if not _gate:
        _gate.append(_CoreGate(run_id))
    return _gate[0]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    gate = _core_gate()
    if gate is None:
        profile = _TestProfile(item)
        yield
        profile.close()
        _forget_last_exception()
        return
    exclusive = item.get_closest_marker("two_cores") is not None
    gate.acquire(exclusive)
    profile = _TestProfile(item)
    try:
        yield
    finally:
        profile.close()
        gate.release(exclusive)
        _forget_last_exception()


def _forget_last_exception() -> None:
    """pytest keeps a failed (or xfailed) test's exception in sys.last_value/last_traceback;
    its frames hold that test's simulations alive, so the next simulation of this worker
    shares the old Taichi runtime and compiles every kernel again instead of reading them
    from the cache (engine/backend.py acquire)."""
    import sys
    for name in ("last_type", "last_value", "last_traceback", "last_exc"):
        if hasattr(sys, name):
            delattr(sys, name)


class RuntimeStarted(BaseException):
    """``check`` (or a scene refused on load) must not initialise Taichi."""


@pytest.fixture
def no_taichi_runtime(monkeypatch):
    """Starting the Taichi runtime (engine/backend.py ``acquire``) raises RuntimeStarted."""
    from taichi_dem.engine import backend

    def refuse(*args, **kwargs):
        raise RuntimeStarted("the Taichi runtime was started (ti.init): kernels would compile")
    monkeypatch.setattr(backend, "acquire", refuse)


# ------------------------------------------------------------------ where the suite's time goes
# TAICHI_DEM_SUITE_PROFILE=FOLDER: each worker appends one JSON line per test to FOLDER: the
# test's wall time (set-up included), its kernels' first launches (compiled, or read from
# Taichi's offline cache; over 0.08 s counted as compiled) and the seconds they took, and how
# many Taichi runtimes it started
# (bench/suite_profile.py sums them by file). Off by default: it changes no test.
_profile: dict = {}


def _profile_start() -> None:
    import os
    folder = os.environ.get("TAICHI_DEM_SUITE_PROFILE")
    if not folder or _profile:
        return
    import time
    from taichi.lang import kernel_impl
    from taichi_dem.engine import backend
    _profile.update(folder=Path(folder), kernels=0, kernel_s=0.0, inits=0, slow=0,
                    front_s=0.0, compiled=[])
    launch = kernel_impl.Kernel.launch_kernel
    # the compiled kernels launched so far (held, so that no id is reused for another)
    seen: set = set()

    def timed(self, t_kernel, *args):
        # a kernel's first launch compiles it (or reads it from the offline cache)
        if t_kernel in seen:
            return launch(self, t_kernel, *args)
        seen.add(t_kernel)
        t0 = time.perf_counter()
        try:
            return launch(self, t_kernel, *args)
        finally:
            dt = time.perf_counter() - t0
            _profile["kernels"] += 1
            _profile["kernel_s"] += dt
            _profile["slow"] += int(dt > 0.08)      # compiled, not read from the cache
            if dt > 0.08:
                _profile["compiled"].append((self.func.__name__, round(dt, 3)))
    kernel_impl.Kernel.launch_kernel = timed
    materialize = kernel_impl.Kernel.materialize

    def front_end(self, *a, **k):
        # the front end (Python AST -> Taichi IR) runs for every new kernel instance, cached
        # or not: Taichi's offline cache is keyed by the IR it produces
        t0 = time.perf_counter()
        try:
            return materialize(self, *a, **k)
        finally:
            _profile["front_s"] += time.perf_counter() - t0
    kernel_impl.Kernel.materialize = front_end
    acquire = backend.acquire

    def counted(*a, **k):
        before = backend.generation()
        out = acquire(*a, **k)
        _profile["inits"] += int(backend.generation() != before)
        return out
    backend.acquire = counted


def _alive_simulations() -> int:
    """Simulations still on the Taichi runtime (not closed, still referenced): while any
    lives, the next simulation compiles its kernels afresh (engine/backend.py acquire)."""
    import gc
    from taichi_dem.engine import backend
    gc.collect()
    return len(backend._live)


class _TestProfile:
    """Per-test row of the suite profile (above), when it is on."""

    def __init__(self, item):
        import os
        import time
        self.item = item
        self.on = bool(os.environ.get("TAICHI_DEM_SUITE_PROFILE"))
        if self.on:
            _profile_start()
            self.start = (_profile["kernels"], _profile["kernel_s"], _profile["inits"],
                          _profile["slow"], time.perf_counter())
            self.front = _profile["front_s"]
            _profile["compiled"] = []

    def close(self) -> None:
        if not self.on:
            return
        import json
        import os
        import time
        k0, s0, i0, c0, t0 = self.start
        row = {"test": self.item.nodeid, "wall_s": time.perf_counter() - t0,
               "kernels": _profile["kernels"] - k0, "kernel_s": _profile["kernel_s"] - s0,
               "inits": _profile["inits"] - i0, "slow_kernels": _profile["slow"] - c0,
               "front_s": _profile["front_s"] - self.front, "compiled": _profile["compiled"],
               "end": time.time(), "alive_after": _alive_simulations()}
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        _profile["folder"].mkdir(parents=True, exist_ok=True)
        with open(_profile["folder"] / f"{worker}.jsonl", "a") as out:
            out.write(json.dumps(row) + "\n")
