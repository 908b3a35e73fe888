"""The one place ``ti.init`` is called.

Taichi has one runtime per process and ``ti.init`` invalidates every field of the old one
(touching a stale field segfaults). Simulations therefore share the runtime: the first one
initialises it with its arch and precision, later ones with the same arch and precision reuse
it. Asking for a different arch or precision re-initialises the runtime; every simulation still
alive on the old runtime is then marked stale and refuses further use with a clear error
instead of crashing. Float literals in kernels take the runtime's default float type, which is
why precision is a runtime setting and not only a field dtype.
"""
from __future__ import annotations

import gc
import os
import sys
import time
import weakref
from pathlib import Path

import taichi as ti

from ..errors import BackendError
from . import frontend

_ARCHES = {
    "cpu": lambda: ti.cpu,
    "gpu": lambda: ti.gpu,
    "cuda": lambda: ti.cuda,
    "vulkan": lambda: ti.vulkan,
    "metal": lambda: ti.metal,
}
_current: dict = {"arch": None, "precision": None, "generation": 0, "threads": None}
_live: "weakref.WeakSet" = weakref.WeakSet()


def real_type(precision: str):
    """Taichi float type for ``"f32"`` or ``"f64"``."""
    return ti.f64 if precision == "f64" else ti.f32


# Taichi holds its kernel cache's lock file only while it reads or writes the cache (at most
# 0.1 s, watched over a whole test suite); a process killed meanwhile leaves the file behind,
# and from then on every run fails to take the lock ("Lock ... ticache.lock failed"), reads no
# cache and compiles every kernel again (the main demo: 3 min 2 s instead of 2 min 33 s,
# measured 2026-12-02). A lock this old is such a leftover. (It was 600 s: a test that kills
# a sweep as it writes the cache left one in a suite run, and the runtimes started in the next
# ten minutes compiled 4,919 kernels, 385 s of the two workers' time.)
STALE_CACHE_LOCK_SECONDS = 15.0

# Taichi's own IR optimisation (``opt_level``): 1, Taichi's default, runs its simplification
# passes before LLVM; 0 skips them (LLVM optimises at -O3 either way). On this CPU 0 compiles
# the main demo in 7.4 s instead of 16.1 s (cold) and steps the chute and the seed's cooler
# slice at the same rate (bench/opt_level.py, BENCHMARKS.md "Compile time: Taichi's IR
# optimisation"); the arithmetic is the same to round-off. A GPU keeps Taichi's default
# (not measured there).
DEFAULT_OPT_LEVEL = {"cpu": 0}


def kernel_cache_dir() -> Path:
    """Where Taichi keeps its offline kernel cache: $TI_OFFLINE_CACHE_FILE_PATH, else
    ~/.cache/taichi/ticache (its default)."""
    path = os.environ.get("TI_OFFLINE_CACHE_FILE_PATH")
    return Path(path) if path else Path.home() / ".cache" / "taichi" / "ticache"


def clear_stale_cache_lock(cache_dir: "Path | str | None" = None,
                           max_age: float = STALE_CACHE_LOCK_SECONDS) -> bool:
    """Remove Taichi's kernel-cache lock file if it is older than ``max_age`` seconds (a
    leftover of a killed process: see STALE_CACHE_LOCK_SECONDS), saying so on stderr.
    Returns whether one was removed."""
    lock = Path(cache_dir if cache_dir is not None else kernel_cache_dir()) / "ticache.lock"
    try:
        age = time.time() - lock.stat().st_mtime
    except OSError:
        return False
    if age < max_age:
        return False
    try:
        lock.unlink()
    except OSError:
        return False
    print(f"taichi-dem: note: removed a stale lock of Taichi's kernel cache ({lock}, "
          f"{age:.0f} s old, left by a process killed while writing the cache); "
          f"without it every run compiled all its kernels again", file=sys.stderr)
    return True


def _nothing_lives() -> bool:
    """Whether no simulation lives on the runtime: all closed, or garbage (collected here:
    a simulation holds reference cycles, so dropping it does not free it at once)."""
    if len(_live) == 0:
        return True
    gc.collect()
    return len(_live) == 0


def acquire(owner, arch: str = "cpu", precision: str = "f32", threads: int | None = None) -> int:
    """Make sure the runtime runs ``arch`` with ``precision``; register ``owner`` as living on
    it. Returns the runtime generation the owner must match to stay valid.

    A runtime on which no simulation lives any more is started afresh. Taichi numbers the
    fields of a runtime in the order they are made and its kernel cache keys name those
    numbers, so on a used runtime every new simulation compiles all its ~50 kernels again
    (~4 s here, bench/jit_probe.py); on a fresh one a scene compiled before - in this process
    or another - is read from the cache (~1 s)."""
    if arch not in _ARCHES:
        raise BackendError(f"unknown arch '{arch}'; choose one of {', '.join(_ARCHES)}")
    if _current["arch"] != arch or _current["precision"] != precision or _nothing_lives():
        for other in list(_live):
            other._mark_stale(f"the Taichi runtime was re-initialised for arch={arch}, "
                              f"precision={precision} by another simulation")
        clear_stale_cache_lock()
        frontend.apply()
        kwargs = dict(arch=_ARCHES[arch](), default_fp=real_type(precision), default_ip=ti.i32,
                      log_level=ti.WARN, offline_cache=True,
                      # the state transfer (transfer.py) unrolls over the fields on purpose:
                      # one kernel copies them all; without this Taichi warns on every scene
                      # with more than 32 fields (a SyntaxWarning on the user's stderr)
                      unrolling_limit=0)
        if threads:
            kwargs["cpu_max_num_threads"] = threads
        kwargs["opt_level"] = ir_optimisation_level(arch)
        ti.init(**kwargs)
        _settle_field_numbering()
        _current.update(arch=arch, precision=precision, generation=_current["generation"] + 1,
                        threads=threads)
    _live.add(owner)
    return _current["generation"]


def ir_optimisation_level(arch: str = "cpu") -> int:
    """Taichi's ``opt_level`` for ``arch``: $TAICHI_DEM_OPT_LEVEL (0 or 1), else
    DEFAULT_OPT_LEVEL's (see there; 1 where it names none)."""
    value = os.environ.get("TAICHI_DEM_OPT_LEVEL", "")
    if value == "":
        return DEFAULT_OPT_LEVEL.get(arch, 1)
    if value not in ("0", "1"):
        raise BackendError(f"TAICHI_DEM_OPT_LEVEL={value!r}: expected 0 or 1")
    return int(value)


def _settle_field_numbering() -> None:
    """Launch an empty kernel on the fresh runtime. Taichi's first kernel launch before any
    field takes a SNode number for an empty root; whether that launch comes before the first
    simulation's fields (the once-per-process workers' probe) or not would otherwise shift
    all their numbers, and Taichi's kernel-cache keys name them: the first simulation of a
    process would share no cached kernel with the later ones (or with other processes')."""
    @ti.kernel
    def nothing():
        pass

    nothing()


def release(owner) -> None:
    """``owner`` (a closed simulation) no longer lives on the runtime."""
    _live.discard(owner)


def cpu_threads() -> int | None:
    """Threads a CPU runtime runs parallel loops on (None on a GPU)."""
    if _current["arch"] != "cpu":
        return None
    return _current["threads"] or os.cpu_count() or 1


def generation() -> int:
    return _current["generation"]


def describe() -> str:
    return f"{_current['arch']} ({_current['precision']})"
