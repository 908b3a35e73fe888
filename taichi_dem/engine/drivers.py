"""The drivers of the step: three ways to run the same step functions (``StepFunctions``,
built by stepper.py) over a number of steps, chosen by the engine's loop mode.

per stage   one launch per stage and step (``drift``, ``pair_forces``, each cell effect's
            ``after_pairs``, ``gather``): a GPU, one core, or workers that gave way
runs       ``run_steps``: up to a rebuild, several whole steps in one launch with every loop
            on one thread (the serial mode, below PARALLEL_FROM particles)
workers    ``run_worker_steps``: the same runs on the engine's persistent worker threads
            (workers.py), which meet at spin barriers between the stages

The host only rebuilds the neighbour lists between the launches (Engine.rebuild). The
drivers hold no physics: the pair stage, the cell stage and the particle stage (with the next
step's drift fused in) are the step functions, the same ti.funcs in every mode.
"""

import taichi as ti

from ..setup import tuning
from .state import Flag
from ..setup.tuning import STALL_SPINS, STALL_SPINS_PER_PARTICLE, WORKER_CHUNK
from .workers import WORKER_TASK, make_barrier


class StepFunctions:
    """The step as ti.funcs of one engine (stepper.py): ``pair_particle(i, dt, full, scatter,
    copy)``, ``gather_particle(i, dt, record, then_drift, t_next, scatter)``,
    ``begin_step(j, t, last, record_last, full_first, leader)``, ``before_pairs(i)`` (None,
    or what each particle prepares after begin_step for every particle's pair stage: run for
    all before any pair), the cell effects' ti.funcs
    ``cell_funcs`` (n, dt), and what the drivers read: the engine's ``flags``, its particle
    ``state`` and its precision ``real``. One thread (a run of steps) adds partners' shares to
    the partners directly, held particles' too (``scatter`` = True)."""

    def __init__(self, **members):
        self.__dict__.update(members)


def compile_run_steps(step: StepFunctions):
    """The serial mode's runs of steps: a kernel run_steps(n, dt, t_first, dt_time, steps,
    full_first, record_last, drift_last) -> steps done."""
    flags, real = step.flags, step.real
    pair_particle, gather_particle, begin_step = (step.pair_particle, step.gather_particle,
                                                  step.begin_step)
    before_pairs = step.before_pairs
    has_before_pairs = before_pairs is not None
    cell_funcs = step.cell_funcs

    @ti.kernel
    def run_steps(n: ti.i32, dt: real, t_first: ti.f64, dt_time: ti.f64, steps: ti.i32,
                  full_first: ti.i32, record_last: ti.i32, drift_last: ti.i32) -> ti.i32:
        """Up to ``steps`` whole steps in one launch, every loop on one thread: the serial
        mode's answer to launch costs (~15 us a launch, against the ~100 us a parallel
        loop costs to dispatch). Step j is at t_first + j dt_time (s): the bodies' frames,
        the pair stage, the cell stage, the particle stage, then the next drift (not after
        the last step unless ``drift_last``). It stops before a step whose neighbour lists
        the previous drift invalidated (Flag.REBUILD): the host rebuilds and goes on.
        ``full_first``: the first step follows a rebuild (held particles' pairs are judged
        then); ``record_last``: the last step books the wall loads. Returns the steps done."""
        done = 0
        ti.loop_config(serialize=True)
        for j in range(steps):
            if j > 0 and flags[Flag.REBUILD] != 0:
                break
            t = t_first + j * dt_time
            last = j == steps - 1
            record, full = begin_step(j, t, last, record_last, full_first, True)
            if ti.static(has_before_pairs):
                for i in range(n):
                    before_pairs(i)
            for i in range(n):
                pair_particle(i, dt, full, ti.static(True), 0)
            for cell_stage in ti.static(cell_funcs):
                cell_stage(n, dt)
            then_drift = 1
            if last:
                then_drift = drift_last
            for i in range(n):
                gather_particle(i, dt, record, then_drift, t + dt_time, 1)
            done += 1
        return done

    return run_steps


def compile_run_worker_steps(step: StepFunctions, pool):
    """The runs of steps on the persistent workers of ``pool`` (workers.WorkerPool): a kernel
    run_worker_steps(n, dt, t_first, dt_time, steps, full_first, record_last, drift_last) ->
    (steps done, barrier waits that stalled)."""
    flags, real, s = step.flags, step.real, step.state
    pair_particle, gather_particle, begin_step = (step.pair_particle, step.gather_particle,
                                                  step.begin_step)
    before_pairs = step.before_pairs
    has_before_pairs = before_pairs is not None
    cell_funcs = step.cell_funcs
    workers = pool.workers
    arrivals, claims, outcome = pool.arrivals, pool.claims, pool.outcome
    has_cells = len(cell_funcs) > 0
    barrier = make_barrier(arrivals, workers)
    copies = pool.copies
    worker_first = pool.first
    chunks_per_worker = tuning.WORKER_CHUNKS

    @ti.func
    def cut_ranges(n):
        """The workers' fixed ranges of the pair stage when they add the partner shares to
        copies of their own (``copies``): fixed, so that the sums' order, and so the
        results, do not depend on the threads' timing; contiguous (cell-sorted: a worker's
        partners are mostly its own particles); cut at equal shares of the pair stage's
        work, one per owned entry and one per particle. Worker w's range starts at
        worker_first[w]. One serial pass (~0.5 ns a particle), at the start of a run."""
        work = ti.i64(0)
        for i in range(n):
            work += s.row_owned[i] + 1
        total_work = work
        worker_first[0] = 0
        for w in range(1, workers):
            worker_first[w] = n
        worker_first[workers] = n
        work = ti.i64(0)
        w = 1
        for i in range(n):
            # the first particle whose work starts at or past w / T of the total
            while w < workers and work * workers >= total_work * w:
                worker_first[w] = i
                w += 1
            work += s.row_owned[i] + 1

    @ti.func
    def claim(stage):
        """The next chunk of particles of ``stage`` (the counter stage % 3, which worker 0
        zeroes one stage ahead: its last use ended two barriers ago)."""
        return ti.atomic_add(claims[stage % 3], 1)

    @ti.kernel
    def run_worker_steps(n: ti.i32, dt: real, t_first: ti.f64, dt_time: ti.f64, steps: ti.i32,
                         full_first: ti.i32, record_last: ti.i32,
                         drift_last: ti.i32) -> ti.types.vector(2, ti.i32):
        """run_steps on ``workers`` threads at once (WORKER_TASK): per step the pair
        stage (each worker its fixed range, cut_ranges, with copies of the sums of its
        own; else over chunks the workers claim), the cell stage (worker 0) and the
        particle stage with the next drift (over claimed chunks), with a barrier after
        each. Returns (steps done, barrier waits that stalled)."""
        arrivals[0] = 0
        arrivals[1] = 0
        for k in ti.static(range(3)):
            claims[k] = 0
        outcome[0] = 0
        outcome[1] = 0
        chunk = ti.max(WORKER_CHUNK, n // (chunks_per_worker * workers))
        chunks = (n + chunk - 1) // chunk
        stall_spins = STALL_SPINS + ti.cast(STALL_SPINS_PER_PARTICLE * n, ti.i32)
        for task in range(workers * WORKER_TASK):
            if task % WORKER_TASK == 0:
                w = task // WORKER_TASK
                arrived = 0
                stalls = 0
                mine_from = 0
                mine_to = 0
                if ti.static(copies > 0):
                    if w == 0:
                        cut_ranges(n)
                    arrived += 1
                    stalls += barrier(arrived, stall_spins)
                    mine_from = worker_first[w]
                    mine_to = worker_first[w + 1]
                done = 0
                for j in range(steps):
                    # (read by all after the last barrier; only a drift sets it)
                    if j > 0 and flags[Flag.REBUILD] != 0:
                        break
                    t = t_first + j * dt_time
                    last = j == steps - 1
                    # (worker 0 zeroes and sets what the particle stage reads after a barrier)
                    record, full = begin_step(j, t, last, record_last, full_first, w == 0)
                    if ti.static(has_before_pairs):
                        # what begin_step set (the bodies' frames), then every particle's
                        # part of the pair stage (over claimed chunks), before any pair
                        if w == 0:
                            claims[(arrived + 1) % 3] = 0
                        arrived += 1
                        stalls += barrier(arrived, stall_spins)
                        if w == 0:
                            claims[(arrived + 1) % 3] = 0
                        c = claim(arrived)
                        while c < chunks:
                            for i in range(c * chunk, ti.min(n, (c + 1) * chunk)):
                                before_pairs(i)
                            c = claim(arrived)
                        arrived += 1
                        stalls += barrier(arrived, stall_spins)
                    if w == 0:
                        claims[(arrived + 1) % 3] = 0
                    if ti.static(copies > 0):
                        # the worker's own range, shares into its own copy
                        for i in range(mine_from, mine_to):
                            pair_particle(i, dt, full, True, w)
                    else:
                        c = claim(arrived)
                        while c < chunks:
                            for i in range(c * chunk, ti.min(n, (c + 1) * chunk)):
                                pair_particle(i, dt, full, False, 0)
                            c = claim(arrived)
                    arrived += 1
                    stalls += barrier(arrived, stall_spins)
                    if ti.static(has_cells):
                        if w == 0:
                            claims[(arrived + 1) % 3] = 0
                            for cell_stage in ti.static(cell_funcs):
                                cell_stage(n, dt)
                        arrived += 1
                        stalls += barrier(arrived, stall_spins)
                    then_drift = 1
                    if last:
                        then_drift = drift_last
                    if w == 0:
                        claims[(arrived + 1) % 3] = 0
                    # (claimed chunks: no race here, and fixed ranges measured no faster
                    # - 1.00x, in-process A/B at 32k - with twice the stalled waits)
                    c = claim(arrived)
                    while c < chunks:
                        for i in range(c * chunk, ti.min(n, (c + 1) * chunk)):
                            gather_particle(i, dt, record, then_drift, t + dt_time,
                                            ti.static(copies))
                        c = claim(arrived)
                    arrived += 1
                    stalls += barrier(arrived, stall_spins)
                    done += 1
                if w == 0:
                    outcome[0] = done
                ti.atomic_add(outcome[1], stalls)
        return ti.Vector([outcome[0], outcome[1]])

    return run_worker_steps


def advance_per_stage(engine, steps: int, record_last: bool):
    """``steps`` steps of ``engine.model.dt`` as one launch per stage and step; the rebuild on the
    host when the drift (or a body) asks for it."""
    e = engine
    dt = e.model.dt
    oldest = e.model.rebuild_within_steps
    lists = e.broadphase
    for k in range(steps):
        n = e.count
        if k == 0:
            # later steps drifted at the end of the previous gather
            e._drift(n, dt, e.time + dt)
        e.time += dt
        rebuild = e.flags[Flag.REBUILD] != 0 or (oldest is not None and lists.list_age >= oldest)
        if e.mesh is not None:
            e.mesh.update_frames(e.time)
            e.mesh.interval_steps += 1
            rebuild = rebuild or e.mesh.needs_rebinning(e.time)
        if rebuild:
            e.rebuild(n)
        lists.list_age += 1
        last = k == steps - 1
        record = 1 if (record_last and last) else 0
        if record:
            e.wall_force.fill(0.0)
            if e.model.heat:
                e.wall_heat.fill(0.0)
        e._pair_forces(e.count, dt, 1 if rebuild else 0)
        for effect in e.model.cell_effects:
            effect.after_pairs(e.context, e.count, dt)    # the gas sees this step's particles
        # the state is left at a whole step (no pending drift) when advance returns
        e._gather(e.count, dt, record, 0 if last else 1, e.time + dt)


def advance_in_runs(engine, steps: int, record_last: bool, on_workers: bool = False):
    """``steps`` steps with run_steps (``on_workers``: run_worker_steps): the host only
    rebuilds, between runs. A run ends at a rebuild the drift flags, at the last step the
    current binning of the bodies' triangles serves, or at ``steps``."""
    e = engine
    pool = e.worker_pool
    dt = e.model.dt
    # an effect that judges at rebuilds (mobility) has the lists rebuilt at least this often
    oldest = e.model.rebuild_within_steps
    lists = e.broadphase
    k = 0
    while k < steps:
        n = e.count
        if k == 0:
            e._drift(n, dt, e.time + dt)   # later runs end with their drift done
        e.time += dt                       # the time of the drifted positions
        rebuild = e.flags[Flag.REBUILD] != 0 or (oldest is not None and lists.list_age >= oldest)
        if e.mesh is not None:
            rebuild = rebuild or e.mesh.needs_rebinning(e.time)
        if rebuild:
            e.rebuild(n)
        run = steps - k
        if e.mesh is not None:
            run = e.mesh.steps_before_rebinning(e.time, dt, run)
        if oldest is not None:
            run = min(run, max(oldest - lists.list_age, 1))
        final = k + run == steps
        args = (e.count, dt, e.time, dt, run, 1 if rebuild else 0,
                1 if (record_last and final) else 0, 0 if final else 1)
        if on_workers:
            done, stalls = (int(v) for v in e._run_worker_steps(*args))
            pool.runs += 1
            # barriers per step: after the pair and the particle stage, the cell stage's,
            # and two around the particles' part of the shields (bodies)
            per_step = 2 + (1 if e.model.cell_effects else 0) + (2 if e.mesh is not None else 0)
            pool.count_stalls(stalls, done * per_step + (1 if pool.copies else 0))
        else:
            done = int(e._run_steps(*args))
        if e.mesh is not None:
            e.mesh.interval_steps += done
        lists.list_age += done
        k += done
        e.time += (done - 1) * dt
