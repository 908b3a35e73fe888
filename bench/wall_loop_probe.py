#!/usr/bin/env python3
"""What a scene costs to compile and to step: build it, run 20 steps with the first call of
every kernel timed (the compile, or the load from Taichi's kernel cache), then 200 steps of
warm-up and ``STEPS`` timed steps.

    TI_OFFLINE_CACHE_FILE_PATH=<folder> python bench/wall_loop_probe.py demos/pile.toml 2000

Used for the plane walls as a loop against the contact law unrolled per wall (BENCHMARKS.md
"Stop 24"): run it twice per fresh cache folder (cold, then warm), per tree.
"""
import sys
import time

from taichi.lang import kernel_impl

_first_calls: dict = {}
_call = kernel_impl.Kernel.__call__


def _timed_call(self, *args, **kwargs):
    before = len(self.compiled_kernels)
    t0 = time.perf_counter()
    out = _call(self, *args, **kwargs)
    if len(self.compiled_kernels) != before:
        name = self.func.__name__
        _first_calls[name] = _first_calls.get(name, 0.0) + time.perf_counter() - t0
    return out


def main(argv) -> int:
    kernel_impl.Kernel.__call__ = _timed_call
    import taichi_dem as td
    path = argv[1]
    steps = int(argv[2]) if len(argv) > 2 else 0
    t0 = time.time()
    sim = td.Simulation.from_toml(path, arch="cpu")
    sim.step(20)
    build = time.time() - t0
    rate = 0.0
    if steps:
        sim.step(200)
        t1 = time.perf_counter()
        sim.step(steps)
        rate = sim.engine.count * steps / (time.perf_counter() - t1) / 1e6
    print(f"build+20 steps {build:.1f} s  run_steps {_first_calls.get('run_steps', 0.0):.2f} s  "
          f"first calls {sum(_first_calls.values()):.1f} s  {rate:.2f} M particle-steps/s")
    sim.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
