#!/usr/bin/env python3
"""What copying N fields to the host costs: Taichi's to_numpy (one kernel per field) against
engine/transfer.py's read (one kernel for the set). Each in its own fresh fields, so both
compile; run twice with the same TI_OFFLINE_CACHE_FILE_PATH for the warm figure:

    TI_OFFLINE_CACHE_FILE_PATH=$(mktemp -d) python bench/transfer_probe.py 40
"""
import sys
import time

import taichi as ti

from taichi_dem.engine import backend, transfer


class _Owner:
    """(backend.acquire registers an owner of the runtime)"""


def fields(n: int):
    return [ti.Vector.field(3, ti.f32, 1000) if k % 3 == 0
            else ti.field(ti.f32 if k % 2 else ti.i32, 1000) for k in range(n)]


if __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    backend.acquire(_Owner(), "cpu", "f32")
    each, bulk = fields(n), fields(n)
    t0 = time.perf_counter()
    for f in each:
        f.to_numpy()
    t1 = time.perf_counter()
    transfer.read(bulk)
    t2 = time.perf_counter()
    print(f"{n} fields: to_numpy each {t1 - t0:.2f} s, one transfer.read {t2 - t1:.2f} s")
