"""Set-up results kept on disk between runs (taichi_dem/setup/memo.py): the same value from
memory, from disk in a "new process" (a fresh wrapper of the same function), and computed
again when the file is damaged or the cache is off."""
import numpy as np

from taichi_dem.setup import memo

calls = []


def slow_square(x, scale=1.0):
    calls.append(x)
    return np.array([x * x * scale])


def test_disk_cache_round_trip(tmp_path, monkeypatch):
    monkeypatch.setenv("TAICHI_DEM_CACHE", str(tmp_path))
    calls.clear()
    first = memo.disk_cached(slow_square)
    assert first(3.0, scale=2.0)[0] == 18.0
    assert first(3.0, scale=2.0)[0] == 18.0          # from memory
    assert calls == [3.0]
    files = list((tmp_path / "memo").glob("*.pkl"))
    assert len(files) == 1
    again = memo.disk_cached(slow_square)             # as a new process would
    assert again(3.0, scale=2.0)[0] == 18.0
    assert calls == [3.0]                             # read from disk, not computed
    assert again(4.0, scale=2.0)[0] == 32.0           # another argument: computed
    assert calls == [3.0, 4.0]
    files[0].write_bytes(b"not a pickle")             # damaged: computed again
    assert memo.disk_cached(slow_square)(3.0, scale=2.0)[0] == 18.0
    assert calls == [3.0, 4.0, 3.0]


def test_cache_off_and_unwritable(tmp_path, monkeypatch):
    monkeypatch.setenv("TAICHI_DEM_CACHE", "off")
    calls.clear()
    assert memo.cache_dir() is None
    assert memo.disk_cached(slow_square)(2.0)[0] == 4.0
    blocked = tmp_path / "file"
    blocked.write_text("a file where the folder should be")
    monkeypatch.setenv("TAICHI_DEM_CACHE", str(blocked))
    assert memo.disk_cached(slow_square)(2.0)[0] == 4.0   # nothing written, still right
    assert calls == [2.0, 2.0]


def test_the_restitution_table_is_the_computed_one(tmp_path, monkeypatch):
    """The damping ratio read through the cache equals the one computed afresh."""
    from taichi_dem.setup import restitution
    monkeypatch.setenv("TAICHI_DEM_CACHE", str(tmp_path))
    cached = restitution._table()
    fresh = restitution._table.__wrapped__()
    np.testing.assert_array_equal(cached[1], fresh[1])
