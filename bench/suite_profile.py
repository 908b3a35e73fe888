#!/usr/bin/env python3
"""Where the test suite's time goes (issue 45 item 2): sums the rows that tests/conftest.py
writes with TAICHI_DEM_SUITE_PROFILE=FOLDER, by test file.

    TAICHI_DEM_SUITE_PROFILE=/tmp/prof python3 tasks.py test
    python bench/suite_profile.py /tmp/prof [--top 40]

Per file: the tests' wall time (set-up included, summed over both workers), the kernels'
first launches and the seconds they took (compiling, or reading Taichi's offline cache), how
many of those took over 0.08 s (compiled) and how many Taichi runtimes were started; then the
front end's seconds and the compiled kernels by name.
"""
from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path


def load(folder: Path) -> list[dict]:
    """Every row of every worker's file."""
    rows = []
    for path in sorted(folder.glob("*.jsonl")):
        for line in path.read_text().splitlines():
            if line.strip():
                row = json.loads(line)
                row["worker"] = path.stem
                rows.append(row)
    return rows


def by_file(rows: list[dict]) -> list[dict]:
    """Rows summed by test file, the slowest first."""
    files: dict = defaultdict(lambda: dict(tests=0, wall_s=0.0, kernels=0, kernel_s=0.0,
                                           slow_kernels=0, inits=0))
    for row in rows:
        f = files[row["test"].split("::", 1)[0]]
        f["tests"] += 1
        for key in ("wall_s", "kernels", "kernel_s", "slow_kernels", "inits"):
            f[key] += row.get(key, 0)
    out = [dict(file=name, **f) for name, f in files.items()]
    return sorted(out, key=lambda f: -f["wall_s"])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args(argv)
    rows = load(args.folder)
    files = by_file(rows)
    total = {k: sum(f[k] for f in files) for k in ("tests", "wall_s", "kernels", "kernel_s",
                                                    "slow_kernels", "inits")}
    print(f"{'file':60s} {'tests':>5s} {'wall s':>7s} {'kernels':>7s} {'first s':>7s} "
          f"{'compiled':>8s} {'inits':>5s}")
    for f in files[:args.top]:
        print(f"{f['file']:60s} {f['tests']:5d} {f['wall_s']:7.1f} {f['kernels']:7d} "
              f"{f['kernel_s']:7.1f} {f['slow_kernels']:8d} {f['inits']:5d}")
    print(f"{'all ' + str(len(files)) + ' files':60s} {total['tests']:5d} {total['wall_s']:7.1f} "
          f"{total['kernels']:7d} {total['kernel_s']:7.1f} {total['slow_kernels']:8d} "
          f"{total['inits']:5d}")
    front = sum(row.get("front_s", 0.0) for row in rows)
    compiled: dict = defaultdict(lambda: [0, 0.0])
    for row in rows:
        for name, seconds in row.get("compiled", []):
            compiled[name][0] += 1
            compiled[name][1] += seconds
    if compiled or front:
        print(f"Taichi's front end (AST -> IR, every new kernel instance, cached or not): {front:.1f} s")
        print("compiled (first launch over 0.08 s), by kernel: " + ", ".join(
            f"{name} {n} ({s:.1f} s)" for name, (n, s) in
            sorted(compiled.items(), key=lambda kv: -kv[1][1])[:12]))
    workers = defaultdict(float)
    spans: dict = {}
    for row in rows:
        workers[row["worker"]] += row["wall_s"]
        if "end" in row:
            lo, hi = spans.get(row["worker"], (float("inf"), 0.0))
            spans[row["worker"]] = (min(lo, row["end"] - row["wall_s"]), max(hi, row["end"]))
    print("per worker (s): " + ", ".join(
        f"{w} {t:.0f} in tests" + (f" of {spans[w][1] - spans[w][0]:.0f} from its first test's start "
                                  f"to its last's end" if w in spans else "")
        for w, t in sorted(workers.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
