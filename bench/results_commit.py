#!/usr/bin/env python3
"""What writing the results costs per sample (recorders/hdf5.py): one sample's series and a
frame of N particles (the nine per-particle datasets of a run with heat), then the flush that
commits it, timed on its own, with the file growing sample by sample as in a run.

    python bench/results_commit.py --particles 20000 100000 --samples 40 --repeats 3

Prints, per particle count, the median over the repeats of the median time per sample (ms)
and the size the file reached. Run it on the revision before a change to the recorder for
the comparison (the script uses only the recorder's public methods).
"""
import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from taichi_dem.recorders.hdf5 import HDF5Recorder  # noqa: E402


def one_run(n: int, samples: int, folder: Path) -> tuple[float, float]:
    """Median seconds per sample and the file's final size (MiB)."""
    rng = np.random.default_rng(0)
    arrays = {"id": np.arange(n), "position": rng.random((n, 3)), "velocity": rng.random((n, 3)),
              "angular_velocity": rng.random((n, 3)), "radius": np.full(n, 0.005),
              "mass": np.full(n, 1e-3), "material": np.zeros(n, np.int32),
              "temperature": rng.random(n) + 300.0, "moisture": rng.random(n)}
    path = folder / f"r{n}.h5"
    rec = HDF5Recorder(str(path), scene_text="", dt=1e-5, arch="cpu", precision="f64")
    times = []
    for k in range(samples):
        series = {"time": 0.01 * k, **{f"s{j}": rng.random() for j in range(60)},
                  "bodies/shell/force": rng.random(3)}
        start = time.perf_counter()
        rec.append_series(series)
        rec.append_frame(0.01 * k, arrays)
        rec.flush()
        times.append(time.perf_counter() - start)
    rec.close()
    return statistics.median(times), path.stat().st_size / 2 ** 20


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--particles", type=int, nargs="+", default=[20000, 100000])
    p.add_argument("--samples", type=int, default=40)
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args(argv)
    for n in a.particles:
        medians, size = [], 0.0
        for _ in range(a.repeats):
            with tempfile.TemporaryDirectory() as d:
                m, size = one_run(n, a.samples, Path(d))
                medians.append(m)
        print(f"{n:>9} particles: {statistics.median(medians) * 1e3:8.2f} ms per sample "
              f"(runs {', '.join(f'{x * 1e3:.2f}' for x in medians)}), file {size:.0f} MiB "
              f"after {a.samples} samples")
    return 0


if __name__ == "__main__":
    sys.exit(main())
