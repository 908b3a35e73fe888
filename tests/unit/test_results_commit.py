"""The results file is committed whole at every sample (recorders/hdf5.py): a writer killed at
any moment, even inside HDF5's own writes, leaves a readable file holding every sample up to
the last commit and nothing of the next one; a resumed writer clears the dead one's side
files. The kills are SIGKILLs the child sends itself from inside a write, at a chosen point,
so each case is hit every time (tests/unit/test_checkpoint_cli.py kills a whole run at a
random moment)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

# the child: 3 samples committed, then a 4th whose write kills the process half way through
# its frame, on the mirror (before the commit) or on the previous file (after it)
CHILD = textwrap.dedent("""
    import os, signal, sys
    import numpy as np
    from taichi_dem.recorders.hdf5 import HDF5Recorder
    path, where = sys.argv[1], sys.argv[2]
    rec = HDF5Recorder(path, scene_text="", dt=1e-5, arch="cpu", precision="f64")
    for k in range(4):
        rec.append_series({"time": 0.1 * k, "mass": [1.0 * k, 2.0]})
        rec.append_frame(0.1 * k, {"id": np.arange(1000), "position": np.full((1000, 3), k, float)})
        if k == 3:
            target = rec._mirror if where == "mirror" else None
            calls = []
            def die(f):
                calls.append(f.filename)
                f["frames/3"].create_dataset("velocity", data=np.zeros((1000, 3)))
                f.flush()                    # part of the sample is in the file...
                if where == "mirror" or len(calls) == 2:
                    os.kill(os.getpid(), signal.SIGKILL)    # ...and the writer dies
            rec._pending.append(die)
        rec.flush()
""")


def _run_child(tmp_path, where):
    path = tmp_path / "r.h5"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", CHILD, str(path), where], env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == -9, r.stderr
    return path


@pytest.mark.parametrize("where, samples", [("mirror", 3), ("previous", 4)])
def test_a_writer_killed_inside_a_write_leaves_whole_results(tmp_path, where, samples):
    """Killed while writing the mirror: the results hold the 3 committed samples. Killed while
    bringing the previous file up to date (after the commit): they hold all 4."""
    path = _run_child(tmp_path, where)
    with h5py.File(path, "r") as f:
        assert list(f["series/time"][()]) == pytest.approx([0.0, 0.1, 0.2, 0.3][:samples])
        assert sorted(f["frames"], key=int) == [str(k) for k in range(samples)]
        for k in range(samples):
            assert np.all(f[f"frames/{k}/position"][()] == k)
        assert f["series/mass"].shape == (samples, 2)
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".r.h5.")]
    assert leftovers, "the dead writer's side files are expected to be there"


def test_a_resumed_writer_continues_the_results_and_clears_dead_side_files(tmp_path):
    from taichi_dem.recorders.hdf5 import HDF5Recorder
    path = _run_child(tmp_path, "mirror")
    rec = HDF5Recorder.continue_at(str(path), 0.1, 1e-5, {"time": [0.0, 0.1]},
                                   scene_text="", arch="cpu", precision="f64")
    rec.append_series({"time": 0.2})
    rec.append_frame(0.2, {"id": np.arange(3), "position": np.zeros((3, 3))})
    rec.close()
    with h5py.File(path, "r") as f:
        assert list(f["series/time"][()]) == pytest.approx([0.0, 0.1, 0.2])
        assert sorted(f["frames"], key=int) == ["0", "1", "2"]
        assert f["frames/2/position"].shape == (3, 3)
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".r.h5.")]


def test_nothing_is_written_in_place(tmp_path):
    """Each flush puts another file at the path (another inode: the mirror; the previous one
    becomes the next mirror), so a crash cannot leave the results half-written."""
    from taichi_dem.recorders.hdf5 import HDF5Recorder
    path = tmp_path / "r.h5"
    rec = HDF5Recorder(str(path), scene_text="", dt=1e-5, arch="cpu", precision="f64")
    inodes = []
    for k in range(3):
        rec.append_series({"time": 0.1 * k})
        rec.flush()
        inodes.append(os.stat(path).st_ino)
        with h5py.File(path, "r") as f:                # readable between samples
            assert len(f["series/time"]) == k + 1
    rec.close()
    assert all(a != b for a, b in zip(inodes, inodes[1:]))
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".r.h5.")]


def test_without_hard_links_each_flush_copies_and_commits_whole(tmp_path, monkeypatch):
    """A file system without hard links (os.link fails): the previous file cannot be kept as
    the next mirror, so each flush copies the results first; the commits stay whole."""
    from taichi_dem.recorders import hdf5

    def no_links(src, dst):
        raise OSError("hard links not supported here")

    monkeypatch.setattr(hdf5.os, "link", no_links)
    path = tmp_path / "r.h5"
    rec = hdf5.HDF5Recorder(str(path), scene_text="", dt=1e-5, arch="cpu", precision="f64")
    for k in range(3):
        rec.append_series({"time": 0.1 * k})
        rec.append_frame(0.1 * k, {"position": np.full((4, 3), float(k))})
        rec.flush()
        assert not rec._mirror_ok
        with h5py.File(path, "r") as f:
            assert len(f["series/time"]) == k + 1 and len(f["frames"]) == k + 1
    rec.close()
    with h5py.File(path, "r") as f:
        assert [float(f[f"frames/{k}/position"][0, 0]) for k in range(3)] == [0.0, 1.0, 2.0]
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".r.h5.")]
