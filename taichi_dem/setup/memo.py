"""Results of slow, pure set-up computations kept on disk between runs (issue 45 item 1).

Some of what a scene's build computes depends only on numbers and takes seconds: the
restitution table of the damped Hertz contact (an ODE integrated for 160 damping ratios), the
transient wall-conductance ratio of a sphere (a sparse solve per time), the gas-gap shares.
Within a process ``functools.lru_cache`` keeps them; ``disk_cached`` keeps them across
processes as the kernel cache keeps the kernels, so a run that starts again does not compute
them again.

The key is the function's module source (a change to the code drops what it computed), its
name and its arguments' ``repr``. Files live under $TAICHI_DEM_CACHE, else
$XDG_CACHE_HOME/taichi_dem, else ~/.cache/taichi_dem (``memo/``); each is written to a
temporary name and renamed, so two processes never read half a file. Anything that goes wrong
with the cache (no home, a read-only disk, a damaged file) falls back to computing: the cache
can make a run faster, never different. TAICHI_DEM_CACHE=off switches it off.
"""
from __future__ import annotations

import functools
import hashlib
import inspect
import os
import pickle
import sys
import tempfile
from pathlib import Path


def cache_dir() -> Path | None:
    """Where the results are kept, or None when switched off."""
    value = os.environ.get("TAICHI_DEM_CACHE")
    if value is not None and value.strip().lower() in ("off", "0", "none", ""):
        return None
    if value:
        return Path(value) / "memo"
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "taichi_dem" / "memo"


def _module_hash(func) -> str:
    try:
        source = inspect.getsource(sys.modules[func.__module__])
    except (OSError, TypeError, KeyError):
        source = func.__qualname__
    return hashlib.sha256(source.encode()).hexdigest()[:16]


def disk_cached(func):
    """``func`` (pure: its result depends on its arguments alone, which have a faithful
    ``repr``; the result pickles) remembered in memory and on disk (module docstring)."""
    version = []

    @functools.lru_cache(maxsize=256)
    def remembered(*args, **kwargs):
        folder = cache_dir()
        if folder is None:
            return func(*args, **kwargs)
        if not version:
            version.append(_module_hash(func))
        key = repr((func.__module__, func.__qualname__, version[0], args,
                    sorted(kwargs.items())))
        path = folder / (hashlib.sha256(key.encode()).hexdigest()[:32] + ".pkl")
        try:
            with open(path, "rb") as f:
                stored_key, value = pickle.load(f)
            if stored_key == key:
                return value
        except Exception:          # absent, damaged or unreadable: compute
            pass
        value = func(*args, **kwargs)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
            with os.fdopen(fd, "wb") as f:
                pickle.dump((key, value), f)
            os.replace(tmp, path)
        except Exception:          # a read-only or full disk: the result is still right
            pass
        return value

    functools.update_wrapper(remembered, func)
    return remembered
