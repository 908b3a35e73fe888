"""Persistent workers on the CPU threads: one parallel range-for whose iterations
WORKER_TASK apart are the workers, each running a serial program and meeting the others at
a spin barrier (~0.1 - 0.2 us on these machines) where a parallel launch, or a parallel loop
of a kernel, would hand its work to Taichi's thread pool again (~40 - 100 us each here,
TAICHI_NOTES). The runs of steps (drivers.py, run_worker_steps) and the rebuild
(Broadphase.rebuild_on_workers) use them. Here: the barrier, the check that a machine's
threads really run at once (once per process), and ``WorkerPool``, one engine's workers with
the fields they meet at and the count of their stalled waits."""

import os
import sys

import taichi as ti

from .state import FieldTree
from ..setup.tuning import PROBE_SPINS, WORKER_STALL_LIMIT, WORKER_STALL_WINDOW, WORKER_STALLED_WINDOWS

WORKER_TASK = 512       # loop iterations per worker: its one active iteration is alone in its task
# (Taichi cuts a CPU range-for into tasks of 512 - 1024 iterations - its adaptive block size,
# which ti.loop_config(block_dim=...) does not change - or of 32 without it: iteration
# w * 512 starts a task of its own either way, so no thread is handed two workers and waits
# for itself; a loop of 512 iterations or fewer runs on one thread)


def make_barrier(arrivals, workers: int):
    """A ti.func barrier(arrived, stall_spins) for ``workers`` workers counting their
    arrivals in ``arrivals`` (an i32 field of 2, both zeroed at the launch's start): arrive
    at the ``arrived``-th barrier of this launch and wait for every worker; returns 1 if the
    wait stalled (past ``stall_spins`` spins: a worker had lost its core)."""

    @ti.func
    def barrier(arrived, stall_spins):
        ti.atomic_add(arrivals[0], 1)
        spins = 0
        # (an atomic read: a plain load could stay in a register across the loop)
        while ti.atomic_add(arrivals[0], arrivals[1]) < arrived * workers:
            spins += 1
        return 1 if spins > stall_spins else 0

    return barrier


@ti.func
def worker_range(count, w, workers):
    """Worker ``w``'s share [first, last) of ``count`` items cut into ``workers`` equal
    contiguous ranges."""
    return count * w // workers, count * (w + 1) // workers


# ------------------------------------------------------------------ the workers of a process
_probe_result: dict = {}     # per worker count; "gave way": see WorkerPool.count_stalls


def persistent_workers(threads) -> int:
    """Workers of the runs of steps on every thread (0: not used): the CPU threads when there
    are two or more, no more than the cores this process may run on (a worker waiting for a
    core would spin), unless an engine of this process found its workers stalling (the cores
    are shared: later simulations start with the launches) or $TAICHI_DEM_WORKERS is 0, and
    once per runtime a check that they really run at once."""
    if not threads or threads < 2 or os.environ.get("TAICHI_DEM_WORKERS", "1") == "0":
        return 0
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:          # (not on Linux)
        cores = os.cpu_count() or 1
    if threads > cores or _probe_result.get("gave way") or not _workers_run_together(threads):
        return 0
    return threads


def _workers_run_together(workers: int) -> bool:
    """Whether ``workers`` iterations WORKER_TASK apart of one CPU range-for run on as many
    threads at once: each arrives at a barrier and waits (PROBE_SPINS at most) for the
    others. Once per process: a property of the machine (backend.acquire starts a fresh
    runtime for a simulation when no other lives)."""
    key = workers
    if key not in _probe_result:
        # ndarrays, not fields: a field here would take SNode numbers before the first
        # simulation's own fields, and Taichi's kernel-cache keys name those numbers, so the
        # first simulation of a process would never share cached kernels with later ones
        arrivals = ti.ndarray(ti.i32, 2)
        met = ti.ndarray(ti.i32, 1)

        @ti.kernel
        def probe(arrivals: ti.types.ndarray(dtype=ti.i32, ndim=1),
                  met: ti.types.ndarray(dtype=ti.i32, ndim=1)):
            arrivals[0] = 0
            arrivals[1] = 0
            met[0] = 0
            for task in range(workers * WORKER_TASK):
                if task % WORKER_TASK == 0:
                    ti.atomic_add(arrivals[0], 1)
                    spins = 0
                    while ti.atomic_add(arrivals[0], arrivals[1]) < workers and spins < PROBE_SPINS:
                        spins += 1
                    if spins < PROBE_SPINS:
                        ti.atomic_add(met[0], 1)

        probe(arrivals, met)
        _probe_result[key] = int(met[0]) == workers
    return _probe_result[key]


class WorkerPool:
    """The persistent workers of one engine: how many (``workers``, 0: none, or no longer),
    the fields their launches meet at (barrier arrivals, chunk claims, the outcome, and with
    ``copies`` each worker's own copy of the partner-share sums), and the count of their
    barrier waits that stalled, by which they give way to the parallel kernels when the cores
    are shared with other work. Nothing of the physics: the run kernel is drivers.py's."""

    # the stalled share of barrier waits, judged over windows of STALL_WINDOW waits, at which
    # the workers give way (None: never, for tests and benchmarks; tuning.py)
    stall_limit: "float | None" = WORKER_STALL_LIMIT
    STALL_WINDOW = WORKER_STALL_WINDOW
    STALLED_WINDOWS = WORKER_STALLED_WINDOWS

    def __init__(self, workers: int, capacity: int, real, heat: bool, copies: bool):
        self.workers = workers
        self.runs = 0                 # runs of steps done on the workers
        self.give_way = False
        self.barriers = self.stalls = 0
        self.window_barriers = self.window_stalls = 0
        self.stalled_windows = 0
        self.tree = None
        # worker w adds the shares of the pairs it computes to copy w - copy 0 is the serial
        # mode's scattered_* sums (ParticleState), these are copies 1 .. T-1 - and the particle
        # stage adds a particle's copies in order and clears them; zero between steps, so a
        # checkpoint neither holds nor needs them
        self.copies = workers if (workers and copies) else 0
        self.copy_force = self.copy_torque = self.copy_heat = self.copy_conductance = None
        self.first = None
        if not workers:
            return
        # (kept out of the engine's trees: a checkpoint neither holds nor needs it)
        wt = self.tree = FieldTree()
        # [arrivals at barriers, 0 (read to keep the spin-wait an atomic)]
        self.arrivals = wt.add("worker_arrivals", ti.i32, 2)
        self.claims = wt.add("worker_claims", ti.i32, 3)   # chunk counters
        self.outcome = wt.add("worker_outcome", ti.i32, 2)
        extra = max(self.copies - 1, 0)
        if self.copies:
            # where each worker's range of the pair stage starts (cut_ranges), and n
            self.first = wt.add("worker_first", ti.i32, workers + 1)
        if extra:
            self.copy_force = wt.add("copy_force", real, (extra, capacity), vector=True)
            self.copy_torque = wt.add("copy_torque", real, (extra, capacity), vector=True)
            if heat:
                self.copy_heat = wt.add("copy_heat", real, (extra, capacity))
                self.copy_conductance = wt.add("copy_conductance", real, (extra, capacity))
        wt.finalize()

    def count_stalls(self, stalls: int, barriers: int):
        """Book a run on the workers: ``barriers`` waits of which ``stalls`` stalled. When more
        than ``stall_limit`` of the waits stalled in STALLED_WINDOWS windows in a row, the
        threads are sharing the cores with other work (two test processes, a sweep's
        workers) and each spin-wait costs a scheduler slice: the engine goes on with the
        parallel kernels (the same physics; the partners' shares are then gathered, an order
        of sums that differs by round-off)."""
        self.stalls += stalls
        self.barriers += barriers
        self.window_stalls += stalls
        self.window_barriers += barriers
        if self.window_barriers < self.STALL_WINDOW:
            return
        window_stalls, window_barriers = self.window_stalls, self.window_barriers
        self.window_stalls = self.window_barriers = 0
        limit = self.stall_limit
        if limit is None or window_stalls <= limit * window_barriers:
            self.stalled_windows = 0
            return
        # (two windows in a row: a slow phase of a shared host passes, other work stays)
        self.stalled_windows += 1
        if not self.give_way and self.stalled_windows >= self.STALLED_WINDOWS:
            print(f"taichi-dem: note: {window_stalls} of {window_barriers} barrier "
                  f"waits of the {self.workers} worker threads stalled (the cores are shared "
                  f"with other work); going on with one parallel launch per stage, in this "
                  f"process's later simulations too",
                  file=sys.stderr)
            self.give_way = True              # from the next advance on (a run is under way)
            _probe_result["gave way"] = True  # and later engines of this process start so

    def destroy(self):
        if self.tree is not None:
            self.tree.destroy()
            self.tree = None
