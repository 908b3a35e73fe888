"""The command line around checkpoints: a run killed with SIGKILL keeps readable results and
checkpoint files; a diverging scene exits 3 with a checkpoint that `resume` loads; --quiet
and the progress line; --window without a display. Each test runs the CLI in a subprocess
(its own Taichi runtime)."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from resume_scene import scene_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def cli(*args, **kw):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "taichi_dem", *map(str, args)], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=300, **kw)


# ten beads of a jelly far too soft (E = 1 kPa) for their weight fall onto a floor: each
# sinks through it. The loader accepts the scene (nothing in it is invalid), and the first
# impacts overlap by more than 0.6 of the radius.
SOFT = """
[simulation]
end_time = 0.5
gravity = [0.0, 0.0, -9.81]
precision = "f64"
seed = 2

[domain]
min = [-0.03, -0.03, -0.01]
max = [0.03, 0.03, 0.1]

[[walls]]
name = "floor"
plane = { point = [0, 0, 0], normal = [0, 0, 1] }
material = "steel"

[materials.jelly]
density = 2500.0
youngs_modulus = 1000.0
poisson_ratio = 0.25

[materials.steel]
density = 7800.0
youngs_modulus = 2e11
poisson_ratio = 0.3

[[interactions]]
pair = ["jelly", "jelly"]
restitution = 0.5
friction = 0.5

[[interactions]]
pair = ["jelly", "steel"]
restitution = 0.5
friction = 0.5

[[particles]]
material = "jelly"
radius = 0.004
count = 10
region = { box = { min = [-0.025, -0.025, 0.02], max = [0.025, 0.025, 0.06] } }

[output]
interval = 0.01
"""


def _last_own_line(stderr: str) -> str:
    """The last line taichi-dem wrote: Taichi's own warnings (e.g. a kernel-cache lock held by
    a parallel test process, "[W ...]") may come after it and are not ours."""
    return [line for line in stderr.strip().splitlines()
            if not line.startswith("[W ") and not line.startswith("[Taichi]")][-1]


def test_divergence_exits_3_with_a_checkpoint_that_resume_loads(tmp_path):
    scene = tmp_path / "soft.toml"
    scene.write_text(SOFT)
    out = tmp_path / "out"
    r = cli("run", scene, "--out", out, "--quiet")
    assert r.returncode == 3, r.stderr
    # the message is the last line taichi-dem writes; Taichi's own warnings (a kernel-cache
    # lock held by a parallel test process) may come after it and are not ours
    message = _last_own_line(r.stderr)
    # when, which particle, where, why, the fix, and the checkpoint
    for part in ("diverged at t = ", "particle ", " at (", "overlaps", "Likely cause",
                 "Fix:", "youngs_modulus", "soft.checkpoint.h5"):
        assert part in message, message
    assert "Traceback" not in r.stderr
    checkpoint = out / "soft.checkpoint.h5"
    with h5py.File(checkpoint, "r") as f:
        t_good = float(f.attrs["time"])
        t_series = f["series/time"][()]
    t_bad = float(message.split("diverged at t = ")[1].split(" s")[0])
    # the last good state is the sample before the divergence (output interval 0.01 s)
    assert 0 < t_good < t_bad and t_bad - t_good < 0.011
    assert t_series[-1] == pytest.approx(t_good)
    # resume loads it and continues to a time just after it (no further impact yet) ...
    r2 = cli("resume", checkpoint, "--until", t_good + 0.0005)
    assert r2.returncode == 0, r2.stderr
    assert f"resumed at t = {t_good:.6g} s" in r2.stderr
    # ... and, run on, diverges again at the same time and particle (the same state)
    r3 = cli("resume", checkpoint, "--quiet")
    assert r3.returncode == 3
    assert _last_own_line(r3.stderr).split(" Likely")[0] == message.split(" Likely")[0]


def test_sigkill_mid_run_leaves_readable_results_and_checkpoint(tmp_path):
    scene = tmp_path / "drum.toml"
    # a checkpoint at every sample, so the kill has many chances to land inside one
    scene.write_text(scene_text("f32", extra="checkpoint_interval = 0.005").replace(
        "end_time = 0.1", "end_time = 100.0"))
    out = tmp_path / "out"
    # a progress line into the log every 0.5 s (default 10 s), so the kill lands near t = 0.08 s
    env = dict(os.environ, PYTHONPATH=str(ROOT), TAICHI_DEM_PROGRESS_S="0.5")
    log = open(tmp_path / "stderr.txt", "w")
    proc = subprocess.Popen([sys.executable, "-m", "taichi_dem", "run", str(scene), "--out",
                             str(out)], cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=log)
    deadline = time.time() + 240
    progress = ""
    try:
        while time.time() < deadline:
            progress = (tmp_path / "stderr.txt").read_text()
            # the progress line names simulated time, wall time, particle-steps/s and an ETA
            shown = [float(x.split()[0]) for x in progress.split("t = ")[1:]
                     if "particle-steps/s" in x and "ETA" in x]
            if shown and shown[-1] >= 0.08:
                break
            assert proc.poll() is None, progress
            time.sleep(0.2)
        else:
            pytest.fail("the run made no progress: " + progress)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        log.close()
    with h5py.File(out / "drum.h5", "r") as f:
        times = f["series/time"][()]
        frames = sorted(f["frames"], key=int)
        assert len(frames) >= 16
        # a sample writes its series, then its frame, then flushes: at most one series row
        # more than frames
        assert len(times) in (len(frames), len(frames) + 1)
        for k, name in enumerate(frames):
            g = f["frames"][name]
            assert g.attrs["time"] == pytest.approx(times[k])
            pos = g["position"][()]
            # (the paddle flings the odd bead out of the domain: it is counted as lost)
            assert pos.shape[1] == 3 and 250 <= pos.shape[0] <= 300 and np.all(np.isfinite(pos))
        assert np.all(np.diff(times) > 0)
        assert len(f["series/particles/kinetic_energy"]) >= len(frames)
    from taichi_dem.run import checkpoint
    snap = checkpoint.load(str(out / "drum.checkpoint.h5"))
    assert 0.0 < snap.time <= times[-1] + 1e-9
    assert len(snap.series["time"]) == int(np.searchsorted(times, snap.time + 1e-9))
    # every particle slot: the scene's 300, allocated as a bucket of them (no fewer than the
    # engine's floor of slots)
    from taichi_dem.setup.memory import bucket
    from taichi_dem.setup.tuning import MIN_PARTICLE_SLOTS
    assert snap.fields["position"]["position"].shape == (max(bucket(300), MIN_PARTICLE_SLOTS), 3)


def test_quiet_silences_progress(tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(SOFT.replace("end_time = 0.5", "end_time = 0.03"))
    r = cli("run", scene, "--out", tmp_path, "--quiet")
    assert r.returncode == 0, r.stderr
    assert "particle-steps/s" not in r.stderr and "ETA" not in r.stderr
    assert "simulated" in r.stdout


def test_window_without_display_is_one_line_and_exit_2(tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(SOFT)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PYTHONPATH"] = str(ROOT)
    r = subprocess.run([sys.executable, "-m", "taichi_dem", "run", str(scene), "--window"],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    lines = [x for x in r.stderr.splitlines() if x.startswith("taichi-dem:")]
    assert len(lines) == 1 and "display" in lines[0], r.stderr
    assert "Traceback" not in r.stderr
