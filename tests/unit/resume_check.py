"""Resume equivalence, run in a fresh process so the Taichi runtime gets the thread count
(the runtime is shared per process; see backend.py):

    python tests/unit/resume_check.py --precision f64 --threads 1 --dir /tmp/x

Run A: 0 -> T1 (a periodic checkpoint at T1) -> T2, with a speed change at T0 < T1 and a
host-side checkpointable counter. Run B: resumed from A's checkpoint -> T2, continuing a copy
of A's results file. Prints JSON: the largest differences between A and B at T2.
"""
import argparse
import json
import os
import shutil
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from resume_scene import scene_text  # noqa: E402

T0, T1, T2 = 0.1, 0.15, 0.2


class SampleCounter:
    """A host-side component with state: counts the output samples it has seen."""

    def __init__(self):
        self.samples = 0
        self.history = np.zeros(0)

    def __call__(self, sim, values):
        self.samples += 1
        self.history = np.append(self.history, values["particles/kinetic_energy"])

    def state_dict(self):
        return {"samples": self.samples, "history": self.history}

    def load_state_dict(self, d):
        self.samples = int(d["samples"])
        self.history = np.asarray(d["history"])


def attach_counter(sim):
    counter = SampleCounter()
    sim.checkpointables["counter"] = counter
    sim.add_observer(counter, now=False)
    return counter


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--precision", default="f64")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--dir", required=True)
    a = p.parse_args()
    import taichi_dem as td

    h5_a = os.path.join(a.dir, "a.h5")
    text = scene_text(a.precision, extra=f"checkpoint_interval = {T1}")
    sim = td.Simulation.from_text(text, threads=a.threads, h5=h5_a)
    sim.checkpointer.path = os.path.join(a.dir, "a.checkpoint.h5")
    counter_a = attach_counter(sim)
    sim.run(T0)
    sim.set_speed("paddle", "90 rpm")
    sim.run(T1 + 0.002)                    # past the checkpoint sample
    checkpoint_copy = os.path.join(a.dir, "t1.checkpoint.h5")
    shutil.copy(sim.checkpointer.path, checkpoint_copy)
    sim.run(T2)
    pa, sa, steps_a = sim.particles(), sim.series, sim.step_count
    sim.close()
    h5_b = os.path.join(a.dir, "b.h5")
    shutil.copy(h5_a, h5_b)                # B continues A's file, which runs past T1

    counters = []
    b = td.Simulation.from_checkpoint(checkpoint_copy, threads=a.threads, h5=h5_b,
                                      configure=lambda s: counters.append(attach_counter(s)))
    t_resumed = b.time
    b.run(T2)
    pb, sb = b.particles(), b.series
    out = {"t_resumed": t_resumed, "steps": [steps_a, b.step_count],
           "counter": [counter_a.samples, counters[0].samples],
           "counter_history": float(np.max(np.abs(counter_a.history - counters[0].history))),
           "state": {k: float(np.max(np.abs(pa[k] - pb[k])))
                     for k in ("position", "velocity", "angular_velocity", "temperature")},
           "scale": {k: float(np.max(np.abs(pa[k])))
                     for k in ("position", "velocity", "angular_velocity", "temperature")},
           # NaN where a series is undefined (a coefficient while nothing touches) must be
           # NaN in both runs: it counts as equal there, as a difference anywhere else
           "series": {k: float(np.max(np.where(np.isnan(sa[k]) & np.isnan(sb[k]), 0.0,
                                               np.abs(sa[k] - sb[k]))))
                      if sa[k].shape == sb[k].shape else "shape" for k in sa},
           "series_scale": {k: float(np.nanmax(np.abs(sa[k]), initial=0.0)) for k in sa},
           "speed_after": float(sb["bodies/paddle/angular_speed"][-1]),
           "torque_rms": float(np.sqrt(np.mean(sa["bodies/paddle/axial_torque"] ** 2)))}
    b.close()
    with h5py.File(h5_a, "r") as fa, h5py.File(h5_b, "r") as fb:
        out["file_time"] = [len(fa["series/time"]), len(fb["series/time"]),
                            float(np.max(np.abs(fa["series/time"][()] - fb["series/time"][()])))
                            if len(fa["series/time"]) == len(fb["series/time"]) else -1.0]
        out["file_frames"] = [len(fa["frames"]), len(fb["frames"])]
        last = str(len(fa["frames"]) - 1)
        out["file_last_frame"] = float(np.max(np.abs(fa[f"frames/{last}/position"][()]
                                                     - fb[f"frames/{last}/position"][()])))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
