#!/usr/bin/env python3
"""Kill a results writer at random moments and check every file it leaves (recorders/hdf5.py).

    python bench/results_kill_stress.py 120

A child process creates a results file and commits samples in a tight loop (a series row and a
frame of 2,000 particles each), so most kills land inside a commit; it is SIGKILLed after a
random 0.3 - 2 s. Each file left must open, hold as many series rows as frames, and every
frame's data must be whole. Prints the count of bad files and the frames per file.
"""
import os, random, signal, subprocess, sys, time, tempfile, h5py, numpy as np
CHILD = r'''
import sys, numpy as np
from taichi_dem.recorders.hdf5 import HDF5Recorder
rec = HDF5Recorder(sys.argv[1], scene_text="x", dt=1e-5, arch="cpu", precision="f64")
k = 0
while True:
    rec.append_series({"time": 0.01 * k, "a": [1.0, 2.0, 3.0]})
    rec.append_frame(0.01 * k, {"id": np.arange(2000), "position": np.full((2000, 3), float(k))})
    rec.flush()
    k += 1
'''
random.seed(1)
bad, empty, counts = [], 0, []
N = int(sys.argv[1])
for i in range(N):
    d = tempfile.mkdtemp()
    p = os.path.join(d, "r.h5")
    proc = subprocess.Popen([sys.executable, "-c", CHILD, p])
    time.sleep(random.uniform(0.3, 2.0))
    proc.send_signal(signal.SIGKILL); proc.wait()
    if not os.path.exists(p):
        empty += 1; continue
    try:
        with h5py.File(p, "r") as f:
            t = f["series/time"][()] if "time" in f["series"] else np.zeros(0)
            frames = sorted(f["frames"], key=int)
            assert len(t) == len(frames), (len(t), len(frames))
            for k in frames:
                assert np.all(f["frames"][k]["position"][()] == int(k))
                assert f["frames"][k]["id"].shape == (2000,)
            counts.append(len(frames))
    except Exception as e:
        bad.append(repr(e)[:200])
print(f"{N} kills: {len(bad)} bad, {empty} before the file existed; frames per file min {min(counts)} median {int(np.median(counts))} max {max(counts)}")
for b in bad[:5]: print(b)
