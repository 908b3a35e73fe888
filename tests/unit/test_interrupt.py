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
import pytest

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


class _Finaliser:
    """Sends itself Ctrl-C from inside ``__del__`` and runs on there: where Python's own
    handler's KeyboardInterrupt cannot propagate (it is printed as "Exception ignored" and
    dropped)."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10000):            # the handler runs at one of these bytecodes
            pass


def test_a_ctrl_c_inside_a_finaliser_is_not_lost(monkeypatch):
    from taichi_dem.run import interrupt
    dropped = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: dropped.append(u.exc_type))
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        # Python's handler: the interrupt is raised inside __del__ and dropped
        finaliser = _Finaliser()
        del finaliser
        assert dropped == [KeyboardInterrupt]
        # deferred: the flag survives the finaliser, and the run's next check raises
        with interrupt.deferred():
            finaliser = _Finaliser()
            del finaliser
            with pytest.raises(KeyboardInterrupt):
                interrupt.check()
            interrupt.check()             # (once only)
        assert dropped == [KeyboardInterrupt]
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_deferred_ctrl_c_stops_the_run_where_its_clock_and_state_agree(small_scene_text):
    """Requested before a step of ten output intervals: the run stops after the first chunk,
    with the clock at that chunk's end (Python's handler could stop it anywhere inside
    Engine.advance, the simulation's step count behind its engine's time)."""
    import taichi_dem as td
    from taichi_dem.run import interrupt
    with td.Simulation.from_text(small_scene_text()) as sim, interrupt.deferred():
        every = sim.output_every
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10000):
            pass
        with pytest.raises(KeyboardInterrupt):
            sim.step(10 * every)
        assert sim.step_count == every
        assert sim.time == pytest.approx(sim.engine.time, rel=0, abs=1e-12)
