"""Interrupting a run and closed pipes (issue 48 item 3).

Ctrl-C (SIGINT) during ``taichi-dem run``: the progress line is ended, the summary so far is
printed, the state is checkpointed and the ``resume`` command named, the results file is
closed with its .xdmf, and the exit status is 130. Output into a pipe whose reader stopped
(``taichi-dem ... | head``) ends quietly: no traceback."""
import os
import signal
import subprocess
import sys
import time

import h5py

from conftest import ROOT


def test_ctrl_c_leaves_a_summary_a_checkpoint_and_an_xdmf(tmp_path):
    env = dict(os.environ, TAICHI_DEM_PROGRESS_S="0.2", PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "taichi_dem", "run", str(ROOT / "demos" / "pile.toml"),
           "--out", str(tmp_path), "--until", "100"]
    child = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=env, cwd=tmp_path)
    seen = []
    deadline = time.time() + 300
    while time.time() < deadline:          # until it steps (a progress line)
        line = child.stderr.readline()
        seen.append(line)
        if "particle-steps/s" in line or not line:
            break
    assert "particle-steps/s" in seen[-1], "".join(seen)
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=300)
    err = "".join(seen) + err
    assert child.returncode == 130, err
    assert "interrupted at t = " in err and "Traceback" not in err, err
    assert "taichi-dem resume " in err
    checkpoint = err.split("taichi-dem resume ")[1].split()[0]
    assert os.path.exists(checkpoint)
    assert "\nsimulated " in "\n" + out and "particles: " in out, out
    assert (tmp_path / "pile.xdmf").exists()
    with h5py.File(tmp_path / "pile.h5", "r") as f:
        assert len(f["series/time"]) >= 2 and len(f["frames"]) >= 1


def test_a_reader_that_stops_ends_the_output_quietly():
    child = subprocess.Popen([sys.executable, "-m", "taichi_dem", "demo"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    child.stdout.close()                   # the reader is gone before the listing is written
    err = child.stderr.read().decode()
    child.wait(timeout=120)
    assert child.returncode == 0 and "Traceback" not in err and "BrokenPipe" not in err, err
