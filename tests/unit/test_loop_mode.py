"""The engine's two loop modes (engine/stepper.py): below ``parallel_from`` particles a CPU
runs every loop on one thread with several whole steps per launch (``run_steps``); from it on,
two parallel launches per step. They are the same arithmetic (no floating-point atomics in
the particle state) but for the order in which a particle's partners' shares are added: the
serial mode adds each share to the partner as its owner computes it, the parallel mode
gathers them in the partner's row order. A particle with at most one partner's share gets
the same bits in both (the falling beads below, bit for bit); in a heap they agree to
round-off (test_direct_partner_shares_equal_the_gather_to_round_off). The times handed to
the kernels are formed differently too (t0 + j dt on the device against a running sum on the
host), which moves a turning body's frame by round-off."""
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import taichi_dem as td
from taichi_dem.engine.stepper import Engine
from taichi_dem.engine.workers import WorkerPool

sys.path.insert(0, str(Path(__file__).parent))
from resume_scene import scene_text  # noqa: E402

def walls_only_text():
    """The resume scene without its paddle: planes only, no time-dependent geometry."""
    text = scene_text("f64", count=200)
    head, rest = text.split("[[bodies]]", 1)
    return head + "[[particles]]" + rest.split("[[particles]]", 1)[1]


def heap_text():
    """The planes-only scene with 260 beads poured into a 48 mm square column (four side
    walls): after 4,000 steps a heap in which many beads touch two or more others."""
    text = scene_text("f64", count=260).replace(
        "min = [-0.05, -0.05, -0.053], max = [0.05, 0.05, 0.05]",
        "min = [-0.022, -0.022, -0.053], max = [0.022, 0.022, 0.05]")
    head, rest = text.split("[[bodies]]", 1)
    text = head + "[[particles]]" + rest.split("[[particles]]", 1)[1]
    side = ""
    for name, point, normal in (("x_lo", "[-0.024, 0, 0]", "[1, 0, 0]"),
                                ("x_hi", "[0.024, 0, 0]", "[-1, 0, 0]"),
                                ("y_lo", "[0, -0.024, 0]", "[0, 1, 0]"),
                                ("y_hi", "[0, 0.024, 0]", "[0, -1, 0]")):
        side += (f'[[walls]]\nname = "{name}"\nplane = {{ point = {point}, normal = {normal} }}\n'
                 f'material = "steel"\n\n')
    assert "0.022, 0.022" in text
    return text.replace("[materials.glass]", side + "[materials.glass]")


def run(text, parallel_from, steps, fused=True, workers=False, rebuilds_on_workers=True,
        setup=None):
    """``workers``: above parallel_from, runs of steps on the worker threads (the default
    where there are two cores), rebuilding on them unless not ``rebuilds_on_workers``; else
    two parallel launches per step. ``setup(sim)`` before the steps."""
    sim = td.Simulation.from_text(text, parallel_from=parallel_from)
    sim.engine.fused_rebuilds = fused
    sim.engine.rebuilds_on_workers = rebuilds_on_workers
    if setup is not None:
        setup(sim)
    if workers:
        sim.engine.worker_pool.stall_limit = None     # (two test processes may share the cores)
    else:
        sim.engine.workers = 0
    try:
        sim.step(steps)
        p = sim.particles()
        e = sim.engine
        return dict(position=p["position"], velocity=p["velocity"],
                    temperature=p.get("temperature"), serial=e.serial, runs=e.runs,
                    worker_runs=e.worker_pool.runs, copies=e.worker_pool.copies,
                    rebuilds=e.broadphase.rebuilds, fused=list(e.broadphase.fused_stages),
                    fused_waits=e.broadphase.fused_waits,
                    on_workers=list(e.broadphase.worker_stages),
                    time=e.time, steps=sim.step_count,
                    series={k: np.asarray(v) for k, v in sim.series.items()})
    finally:
        sim.close()


def test_runs_of_steps_equal_parallel_steps_on_planes():
    text = walls_only_text()
    serial = run(text, None, 3000)         # 200 beads: serial, in runs
    parallel = run(text, 0, 3000)          # every step two parallel launches (workers off)
    assert serial["serial"] and serial["runs"] and not parallel["serial"]
    # the beads fell, hit the floor and the lists were rebuilt many times (runs were cut)
    assert serial["rebuilds"] > 10 and serial["rebuilds"] == parallel["rebuilds"]
    assert serial["steps"] == parallel["steps"] == 3000
    assert serial["time"] == pytest.approx(parallel["time"], rel=1e-12)
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(serial[key], parallel[key]), key
    # the floor's force and heat were booked at the same samples
    for name in ("walls/floor/force", "walls/floor/heat_flow"):
        assert np.allclose(serial["series"][name], parallel["series"][name],
                           rtol=1e-9, atol=1e-12), name
        assert np.max(np.abs(parallel["series"][name])) > 0.0, name     # the floor was loaded


_skip_below_two_cores = pytest.mark.skipif(
    len(os.sched_getaffinity(0)) < 2, reason="the worker threads need two cores")


def needs_two_cores(test):
    """Skipped below two cores; marked ``two_cores``, which in a two-worker pytest run makes
    the other worker wait between its tests while this one runs (tests/conftest.py: a spin
    barrier whose partner thread has lost its core waits for the OS to preempt it)."""
    return pytest.mark.two_cores(_skip_below_two_cores(test))


@pytest.fixture(autouse=True)
def workers_allowed(monkeypatch):
    """The worker threads here even where the suite turns them off (tasks.py test: two
    pytest processes fill the cores), and even if another module's simulation in this test
    process found them stalling and sent later ones to the launches."""
    from taichi_dem.engine import workers
    monkeypatch.setenv("TAICHI_DEM_WORKERS", "1")
    workers._probe_result.pop("gave way", None)
    yield
    workers._probe_result.pop("gave way", None)


@needs_two_cores
def test_claiming_workers_equal_the_parallel_kernels_bit_for_bit(monkeypatch):
    """Where the workers do not keep partner shares in copies of their own (forced here with
    WORKER_COPIES; the copies cost memory, one sum per particle per worker) they claim chunks
    of particles in both stages and gather the shares through the mirror index, as the
    parallel kernels do: each particle's sums are added in the same order whichever worker
    takes it, so in the heap (many particles receive two or more partners' shares) the state
    is the parallel kernels' bit for bit, through pouring, impacts and rebuilds."""
    from taichi_dem.setup import tuning
    monkeypatch.setattr(tuning, "WORKER_COPIES", False)
    text = heap_text()
    workers = run(text, 0, 3000, workers=True)
    launches = run(text, 0, 3000)
    assert not workers["serial"] and workers["worker_runs"] > 10
    assert workers["copies"] == 0
    assert launches["worker_runs"] == 0
    assert workers["rebuilds"] > 10 and workers["rebuilds"] == launches["rebuilds"]
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(workers[key], launches[key]), key
    # the walls' loads are sums over particles by atomic adds in both: their order, and so
    # the last bits, depend on the threads' timing
    for name in ("walls/floor/force", "walls/x_lo/force", "walls/floor/heat_flow"):
        assert np.allclose(workers["series"][name], launches["series"][name],
                           rtol=1e-9, atol=1e-12), name
        assert np.max(np.abs(launches["series"][name])) > 0.0, name


@needs_two_cores
def test_workers_with_their_own_copies_repeat_bit_for_bit():
    """The workers' pair stage over fixed ranges, each adding its partners' shares to a copy
    of its own (WorkerPool.copies): the order of every sum is fixed, so two runs through
    pouring, impacts and rebuilds give the same state bit for bit, whatever the threads'
    timing."""
    text = heap_text()
    first = run(text, 0, 3000, workers=True)
    again = run(text, 0, 3000, workers=True)
    assert first["copies"] == 2 and first["worker_runs"] > 10 and first["rebuilds"] > 10
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(first[key], again[key]), key


@needs_two_cores
@pytest.mark.parametrize("scene", ["heap", "paddle"])
def test_rebuild_on_the_workers_equals_the_separate_kernels(scene):
    """The parallel mode's rebuild in one launch on the workers (Broadphase.rebuild_on_workers)
    runs the kernels' bodies row by row, in their order, with a barrier where the kernels
    have a launch: the same state bit for bit through pouring and impacts (rows that grow and
    shrink) and with a turning paddle (its mesh rows listed by the kernels after the
    launch). A rebuild where an array is too small (here the candidate scratch, narrowed
    to 2 per particle at the start) stops after the search, and the host finishes it with
    the kernels."""
    text, steps = (heap_text(), 3000) if scene == "heap" else (scene_text("f64", count=300), 1500)

    def narrow_scratch(sim):
        bp = sim.engine.broadphase
        bp._compile_search(2)
        bp._compact = bp._make_compact(sim.engine.pairs)
    on_workers = run(text, 0, steps, workers=True, setup=narrow_scratch)
    kernels = run(text, 0, steps, workers=True, rebuilds_on_workers=False, setup=narrow_scratch)
    assert on_workers["worker_runs"] > 10 and on_workers["rebuilds"] > 10
    assert on_workers["rebuilds"] == kernels["rebuilds"]
    searched, listed = on_workers["on_workers"]
    # (the first rebuild, with no list yet, is the kernels'; the second meets the narrow
    # scratch, which the host widens)
    assert searched == 1 and searched + listed == on_workers["rebuilds"] - 1
    assert kernels["on_workers"] == [0, 0]
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(on_workers[key], kernels[key]), key
    if scene == "paddle":
        torque = "bodies/paddle/torque"
        assert np.array_equal(on_workers["series"][torque], kernels["series"][torque])


@needs_two_cores
def test_worker_threads_follow_a_turning_paddle():
    """With a body the workers' frames come from t0 + j dt, as in the serial runs (the
    per-step launches: a running sum on the host): equal to round-off."""
    text = scene_text("f64", count=300)
    workers = run(text, 0, 1500, workers=True)
    launches = run(text, 0, 1500)
    assert workers["worker_runs"] > 10
    assert np.max(np.abs(workers["position"] - launches["position"])) < 1e-9
    torque = "bodies/paddle/torque"
    scale = np.max(np.abs(launches["series"][torque]))
    assert scale > 0.0
    assert np.max(np.abs(workers["series"][torque] - launches["series"][torque])) < 1e-6 * scale


@needs_two_cores
def test_stalled_workers_give_way_to_the_parallel_kernels(capsys):
    """Barrier waits that stall (the threads share the cores with other work) send the engine
    to the parallel launches from its next advance on - with a note, and the same results;
    a stall now and then (a noisy machine) does not."""
    text = heap_text()
    sim = td.Simulation.from_text(text, parallel_from=0)
    try:
        e = sim.engine
        e.worker_pool.stall_limit = None             # (another test process may share the cores)
        sim.step(100)
        assert e.worker_pool.runs > 0 and e.workers
        e.worker_pool.stall_limit = WorkerPool.stall_limit
        e.worker_pool.window_barriers = e.worker_pool.window_stalls = 0
        window = WorkerPool.STALL_WINDOW
        e.worker_pool.count_stalls(170, window - 10)       # 8.5 % of a window not yet full: not judged
        assert e.worker_pool.window_barriers == window - 10 and e.worker_pool.stalled_windows == 0
        sim.step(10)                            # (20 more barriers: judged, 8.4 % at least)
        assert e.worker_pool.window_barriers == 0 and e.worker_pool.stalled_windows == 1
        assert e.workers and not e.worker_pool.give_way      # one window: a slow phase, perhaps
        e.worker_pool.count_stalls(30, window - 20)        # 1.5 - 2.5 %: a noisy machine
        sim.step(10)
        assert e.worker_pool.stalled_windows == 0 and not e.worker_pool.give_way
        e.worker_pool.count_stalls(window // 5, window)    # 20 %: the cores are shared
        assert e.worker_pool.stalled_windows == 1 and not e.worker_pool.give_way
        e.worker_pool.count_stalls(window // 5, window)    # and still
        assert e.worker_pool.give_way and "stalled" in capsys.readouterr().err
        runs = e.worker_pool.runs
        sim.step(100)
        assert e.workers == 0 and e.worker_pool.runs == runs
    finally:
        sim.close()
    # and this process's next simulations start with the launches (made after the first is
    # closed: one made while another lives on the runtime compiles every kernel afresh)
    with td.Simulation.from_text(text, parallel_from=0) as later:
        assert later.engine.workers == 0


def test_runs_of_steps_follow_a_turning_paddle():
    text = scene_text("f64", count=300)
    serial = run(text, None, 3000)
    parallel = run(text, 0, 3000)
    assert serial["serial"] and not parallel["serial"]
    # frames from t0 + j dt (device) or a running sum (host): round-off of 1e-16 s in the
    # paddle's angle, grown by 3000 steps of collisions; 1e-9 m is 2.5e-7 bead radii
    assert np.max(np.abs(serial["position"] - parallel["position"])) < 1e-9
    assert np.max(np.abs(serial["temperature"] - parallel["temperature"])) < 1e-9
    torque = "bodies/paddle/torque"
    scale = np.max(np.abs(parallel["series"][torque]))
    assert scale > 0.0                          # the paddle did stir the beads
    assert np.max(np.abs(serial["series"][torque] - parallel["series"][torque])) < 1e-6 * scale


def test_one_launch_rebuild_equals_the_separate_kernels(monkeypatch):
    """The serial mode's rebuild in one launch (Broadphase.fused_rebuild) runs the separate
    kernels' bodies in their order: the same state bit for bit, with a turning paddle (the
    mesh rows too); the first rebuilds stop early where an array must grow, the host
    finishing them with the separate kernels. (From the first rebuild on: no wait for
    quiet lists, FUSED_AFTER_QUIET_REBUILDS.)"""
    from taichi_dem.engine import broadphase
    monkeypatch.setattr(broadphase, "FUSED_AFTER_QUIET_REBUILDS", 0)
    text = scene_text("f64", count=300)
    fused = run(text, None, 3000)
    separate = run(text, None, 3000, fused=False)
    assert fused["serial"] and fused["rebuilds"] > 10
    assert fused["rebuilds"] == separate["rebuilds"]
    assert fused["fused"][2] > 0.9 * fused["rebuilds"]      # most rebuilds were one launch
    assert separate["fused"] == [0, 0, 0]
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(fused[key], separate[key]), key
    torque = "bodies/paddle/torque"
    assert np.array_equal(fused["series"][torque], separate["series"][torque])


def test_one_launch_rebuild_waits_until_the_lists_stop_growing(monkeypatch):
    """fused_rebuild is compiled only after FUSED_AFTER_QUIET_REBUILDS rebuilds in a row
    without a reallocation (each reallocation would compile it again, 4 - 6 s); until then
    and after each growth the rebuilds run as separate kernels, with the same lists: the
    state equals a run that never fuses, bit for bit."""
    from taichi_dem.engine import broadphase
    monkeypatch.setattr(broadphase, "FUSED_AFTER_QUIET_REBUILDS", 10)
    text = scene_text("f64", count=300)
    waiting = run(text, None, 3000)
    separate = run(text, None, 3000, fused=False)
    fused_rebuilds = sum(waiting["fused"])
    # every rebuild with a list (all but the first) ran one way or the other
    assert waiting["fused_waits"] + fused_rebuilds == waiting["rebuilds"] - 1
    assert waiting["fused_waits"] >= 10 and fused_rebuilds >= 10
    # once fused, every later rebuild found its arrays large enough
    assert waiting["fused"][0] == 0
    for key in ("position", "velocity", "temperature"):
        assert np.array_equal(waiting[key], separate[key]), key


class _Stub:
    """choose_loop_mode needs only threads, parallel_from and the current mode."""
    choose_loop_mode = Engine.choose_loop_mode

    def __init__(self, threads, parallel_from):
        self.threads, self.parallel_from, self.serial = threads, parallel_from, False


def test_loop_mode_switches_with_a_band():
    e = _Stub(2, 1000)
    assert e.choose_loop_mode(0) is True
    assert e.choose_loop_mode(1100) is True       # within +20 %: stays serial
    assert e.choose_loop_mode(1250) is False      # past it: parallel
    assert e.choose_loop_mode(900) is False       # within -20 %: stays parallel
    assert e.choose_loop_mode(700) is True
    assert _Stub(1, 1000).choose_loop_mode(10 ** 6) is True      # one thread: always serial
    assert _Stub(None, 1000).choose_loop_mode(0) is False        # a GPU: never serial
    always = _Stub(2, 0)
    assert always.choose_loop_mode(0) is False                   # parallel_from = 0


def test_direct_partner_shares_equal_the_gather_to_round_off():
    """The serial mode adds each pair's partner share to the partner directly, in the owners'
    order (``scattered_*``); the parallel mode gathers the shares through the mirror index,
    in the partner's row order: the same terms added in another order. From one state (a
    checkpoint of a settled heap), one step in each mode must give the same velocities, spins
    and temperatures to f64 round-off, in a heap where many particles receive two or more
    partners' shares (so the order does differ). Between steps the scattered sums are zero."""
    from taichi_dem.run import checkpoint
    text = heap_text()
    with td.Simulation.from_text(text) as sim:
        sim.step(4000)
        snap = checkpoint.capture(sim)
        p = sim.particles()
    # particles receiving >= 2 shares: touching partners with a smaller id (the owners)
    d = p["position"][:, None, :] - p["position"][None, :, :]
    touching = np.linalg.norm(d, axis=2) < (p["radius"][:, None] + p["radius"][None, :])
    np.fill_diagonal(touching, False)
    owners = np.sum(touching & (p["id"][None, :] < p["id"][:, None]), axis=1)
    assert np.sum(owners >= 2) > 50, np.bincount(owners)      # measured: 99 of 260
    states = {}
    modes = [("serial", None), ("parallel", 0)]
    if len(os.sched_getaffinity(0)) >= 2:
        modes.append(("workers", 0))      # shares in the workers' own copies (2 threads)
    for name, parallel_from in modes:
        with td.Simulation.from_text(text, parallel_from=parallel_from) as sim:
            e = sim.engine
            if name == "parallel":
                e.workers = 0
            else:
                e.worker_pool.stall_limit = None
            checkpoint.restore(sim, snap)
            sim.step(1)
            assert e.serial == (name == "serial")
            assert (e.worker_pool.runs == 1) == (name == "workers"), name
            states[name] = sim.particles()
            sums = [e.state.scattered_force, e.state.scattered_torque,
                    e.state.scattered_heat, e.state.scattered_conductance]
            if name == "workers":
                assert e.worker_pool.copies == 2
                pool = e.worker_pool
                sums += [pool.copy_force, pool.copy_torque, pool.copy_heat, pool.copy_conductance]
                # both workers' ranges own pairs whose partners are in the other's
                n, rs = e.count, e.state.row_start.to_numpy()
                assert 0 < np.searchsorted(rs[:n + 1], rs[n] // 2) < n
            for field in sums:
                assert not np.any(field.to_numpy()), field
    serial = states["serial"]
    for other in list(states)[1:]:
        assert np.array_equal(serial["id"], states[other]["id"])
        for key, scale in (("velocity", 1.0), ("angular_velocity", 100.0), ("temperature", 400.0)):
            # one step's kick: a force of ~1e-3 N on 7e-4 kg for dt; round-off ~1e-16 of each term
            assert np.max(np.abs(serial[key] - states[other][key])) < 1e-12 * scale, (other, key)
        # drifted before the forces
        assert np.array_equal(serial["position"], states[other]["position"]), other


def test_held_particles_shares_added_directly_equal_the_gather_to_round_off():
    """With [mobility] holding part of a bed, the serial mode still adds every pair's partner
    share to the partner directly (pair_stage.py ``scatter``): a frozen pair of two held
    particles adds no force (neither is integrated), a pair of a held and a moving particle
    adds the moving one's share. 1200 spheres settled 0.5 s on a floor (f64), judged: a fifth
    of them held, many moving ones touching held ones. From that state, three steps in the serial mode
    (direct shares) and in the parallel kernels (the gather through the mirror index) give
    the same velocities and spins to f64 round-off, and the held ones do not move in either."""
    from conftest import SMALL_SCENE
    from taichi_dem.run import checkpoint
    base = SMALL_SCENE.format(precision="f64", rolling=0.0, count=1200).replace(
        "end_time = 0.02", "end_time = 1.0")
    text = base.replace("min = [-0.05, -0.05, -0.01]",
                        "min = [-0.05, -0.05, -0.01]\nperiodic = [\"x\", \"y\"]")
    text += ("\n[mobility]\nsolid_fraction_threshold = 0.2\ncell_size = 0.016\n"
             "granular_temperature_threshold = 1e-5\n")
    with td.Simulation.from_text(text) as sim:
        sim.run(until=0.5)
        sim.engine.rebuild(sim.engine.count)          # judged now
        sim.step(1)
        snap = checkpoint.capture(sim)
    states, held = {}, {}
    for name, parallel_from in (("serial", None), ("parallel", 0)):
        with td.Simulation.from_text(text, parallel_from=parallel_from) as sim:
            e = sim.engine
            if name == "parallel":
                e.workers = 0
            checkpoint.restore(sim, snap)
            before = sim.particles()
            sim.step(3)
            assert e.serial == (name == "serial")
            states[name] = sim.particles()
            active = e.model.effect("mobility").particle_active.to_numpy()[:e.count]
            ids = (e.state.serial if e.state.process else e.state.particle_id).to_numpy()
            held[name] = np.isin(states[name]["id"], ids[:e.count][active == 0])
            assert np.array_equal(states[name]["position"][held[name]],
                                  before["position"][held[name]]), name
    assert np.array_equal(held["serial"], held["parallel"])
    p, h = states["serial"], held["serial"]
    assert 0.1 * len(h) < np.sum(h) < 0.5 * len(h), np.sum(h)        # measured: 259 of 1200
    d = np.linalg.norm(p["position"][:, None, :] - p["position"][None, :, :], axis=2)
    touching = d < (p["radius"][:, None] + p["radius"][None, :])
    np.fill_diagonal(touching, False)
    assert np.sum(np.any(touching[~h][:, h], axis=1)) > 20        # moving ones on held ones
    for key, scale in (("velocity", 1.0), ("angular_velocity", 100.0)):
        assert np.max(np.abs(p[key] - states["parallel"][key])) < 1e-12 * scale, key
