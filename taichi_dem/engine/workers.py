"""Persistent workers on the CPU threads: one parallel range-for whose iterations
WORKER_TASK apart are the workers, each running a serial program and meeting the others at
a spin barrier (~0.1 - 0.2 us on these machines) where a parallel launch, or a parallel loop
of a kernel, would hand its work to Taichi's thread pool again (~40 - 100 us each here,
TAICHI_NOTES). The runs of steps (Engine.run_worker_steps) and the rebuild
(Broadphase.rebuild_on_workers) use them."""

import taichi as ti

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
