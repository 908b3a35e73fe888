#!/usr/bin/env python3
"""What a kernel launch costs on this machine (issue 14 item 2; engine/stepper.py PARALLEL_FROM):
an empty kernel, one parallel loop over 1,000 elements, four such loops in one kernel (unrolled
with ti.static, each still a parallel task), the same loop serialised, and one field element
read from Python; microseconds per call, for each thread count given.

    .venv/bin/python bench/launch_cost.py --threads 1 2
"""
import argparse
import subprocess
import sys

CHILD = r"""
import time
import taichi as ti
ti.init(arch=ti.cpu, cpu_max_num_threads={threads}, offline_cache=False, log_level=ti.WARN)
n = 1000
a = ti.field(ti.f32, n)
b = ti.field(ti.i32, 4)

@ti.kernel
def parallel(n: ti.i32):
    for i in range(n):
        a[i] += 1.0

@ti.kernel
def parallel4(n: ti.i32):
    for _ in ti.static(range(4)):
        for i in range(n):
            a[i] += 1.0

@ti.kernel
def serial(n: ti.i32):
    ti.loop_config(serialize=True)
    for i in range(n):
        a[i] += 1.0

@ti.kernel
def empty():
    b[0] = 1

def per_call(f, *args, calls=3000):
    f(*args)
    t0 = time.perf_counter()
    for _ in range(calls):
        f(*args)
    return (time.perf_counter() - t0) / calls * 1e6

rows = [per_call(empty), per_call(parallel, n), per_call(parallel4, n), per_call(serial, n),
        per_call(lambda: b[0])]
print(" | ".join(f"{v:.1f}" for v in rows))
"""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args(argv)
    print("| threads | empty kernel | 1 parallel loop | 4 parallel loops | 1 serial loop | field read |")
    print("|---|---|---|---|---|---|")
    for t in a.threads:
        for _ in range(a.repeats):
            r = subprocess.run([sys.executable, "-c", CHILD.format(threads=t)], capture_output=True,
                               text=True, check=True)
            print(f"| {t} | " + r.stdout.strip().splitlines()[-1] + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
