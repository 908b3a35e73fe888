"""A checkpoint of an older format is refused with a message that says so (format 2 added the
f64 temperature residuals of f32 scenes, engine/precision.py)."""
import h5py
import pytest

from taichi_dem.errors import CheckpointError
from taichi_dem.run import checkpoint


def test_older_checkpoint_format_is_refused_with_a_clear_message(tmp_path):
    path = tmp_path / "old.ckpt.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "taichi_dem checkpoint 1"
    with pytest.raises(CheckpointError) as err:
        checkpoint.load(str(path))
    msg = str(err.value)
    assert str(path) in msg and "older taichi_dem" in msg and checkpoint.FORMAT in msg


def test_foreign_hdf5_is_not_a_checkpoint(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "something else"
    with pytest.raises(CheckpointError, match="not a taichi_dem checkpoint"):
        checkpoint.load(str(path))
