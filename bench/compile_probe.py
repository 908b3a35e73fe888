#!/usr/bin/env python3
"""What a changed scene value costs in compiling (issue 45 item 1): builds a scene and steps it,
in a fresh process per variant, and counts the kernels Taichi's offline cache gained.

    python bench/compile_probe.py demos/pile.toml simulation.gravity=[0,0,-9.0] \\
        particles.0.count=+10 --steps 20 [--cache DIR]

Each variant (the scene as it is, then each override alone) runs in its own process with the
same cache folder (a fresh temporary one unless --cache); per variant it prints the build and
first-steps wall times, how many compiled kernels the cache gained ("new kernels"), which
kernels no earlier variant had run (another path through the step, such as a rebuild falling
on another step: these compile once whatever the values) and so how many kernels were compiled
again because a value changed ("recompiled", the figure that should be 0). The unchanged
scene runs twice: its second run is the warm reference. ``key=+N`` adds N to a
number. tests/unit/test_compile_once.py runs it on small scenes.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _one(scene: str, override: str | None, steps: int) -> dict:
    """In this process: build ``scene`` with ``override`` applied and step it ``steps`` times."""
    import time
    import tomllib
    sys.path.insert(0, str(ROOT))
    t0 = time.perf_counter()
    import taichi_dem as td
    from taichi_dem.app.overrides import overridden_text
    t1 = time.perf_counter()
    path = Path(scene)
    text = path.read_text()
    if override:
        key, value = override.split("=", 1)
        if value.startswith("+"):
            node = tomllib.loads(text)
            for part in key.split("."):
                node = node[int(part)] if part.isdigit() else node[part]
            value = node + type(node)(value[1:])
        else:
            try:
                value = json.loads(value)
            except json.JSONDecodeError:      # a string ("30 rpm")
                pass
        text = overridden_text(text, {key: value}, str(path))
    # the kernels this run instantiates (compiled or read from the cache), by name
    from taichi.lang import kernel_impl
    used = set()
    materialize = kernel_impl.Kernel.materialize

    def recording(self, key=None, args=None, arg_features=None):
        if key is None or key not in self.compiled_kernels:
            used.add(self.func.__qualname__)
        return materialize(self, key, args, arg_features)
    kernel_impl.Kernel.materialize = recording
    t2 = time.perf_counter()
    with td.Simulation.from_text(text, base_dir=str(path.parent), source=str(path), h5="") as sim:
        t3 = time.perf_counter()
        sim.step(steps)
        t4 = time.perf_counter()
    return {"import_s": t1 - t0, "build_s": t3 - t2, "steps_s": t4 - t3,
            "kernels": sorted(used)}


def run(scene: str, overrides: list[str], steps: int, cache: str) -> list[dict]:
    """Each variant in its own process (module docstring); rows of what each cost."""
    env = dict(os.environ, TI_OFFLINE_CACHE_FILE_PATH=cache)
    rows = []
    seen: set = set()
    for override in [None, None] + list(overrides):
        before = sum(len(f) for _, _, f in os.walk(cache))
        cmd = [sys.executable, __file__, "--one", scene, "--steps", str(steps)]
        if override:
            cmd += ["--override", override]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"{override or 'the scene'} failed:\n{out.stderr[-3000:]}")
        row = json.loads(out.stdout.strip().splitlines()[-1])
        row["variant"] = override or "unchanged"
        row["new_kernels"] = sum(len(f) for _, _, f in os.walk(cache)) - before
        # kernels no earlier variant ran (another path through the step: a rebuild at
        # another step, say): compiled for the first time, not because a value changed
        row["first_used"] = sorted(set(row["kernels"]) - seen) if seen else []
        row["recompiled"] = max(row["new_kernels"] - len(row["first_used"]), 0) if seen else 0
        seen |= set(row["kernels"])
        rows.append(row)
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("overrides", nargs="*", help="key=value (key=+N adds N)")
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--cache", default=None)
    p.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--override", default=None, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.one:
        print(json.dumps(_one(a.scene, a.override, a.steps)))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        rows = run(a.scene, a.overrides, a.steps, a.cache or tmp)
    print("| variant | build (s) | first steps (s) | new kernels | of them first used | "
          "recompiled |\n|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['variant']} | {r['build_s']:.2f} | {r['steps_s']:.2f} | {r['new_kernels']} "
              f"| {', '.join(r['first_used']) or '-'} | {r['recompiled']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
