"""The kernel cache's lock: a leftover of a killed process is removed, a live one is not."""
import os
import time

from taichi_dem.engine import backend


def test_a_stale_kernel_cache_lock_is_removed_with_a_note(tmp_path, capsys):
    lock = tmp_path / "ticache.lock"
    lock.write_bytes(b"")
    hour_ago = time.time() - 3600.0
    os.utime(lock, (hour_ago, hour_ago))
    assert backend.clear_stale_cache_lock(tmp_path)
    assert not lock.exists()
    err = capsys.readouterr().err
    assert "stale lock" in err and str(lock) in err


def test_a_fresh_kernel_cache_lock_is_left_alone(tmp_path, capsys):
    # another process may hold it right now (it does so for well under a second)
    lock = tmp_path / "ticache.lock"
    lock.write_bytes(b"")
    assert not backend.clear_stale_cache_lock(tmp_path)
    assert lock.exists()
    assert not backend.clear_stale_cache_lock(tmp_path / "missing")
    assert capsys.readouterr().err == ""


def test_the_cache_directory_follows_taichis_variable(monkeypatch, tmp_path):
    monkeypatch.setenv("TI_OFFLINE_CACHE_FILE_PATH", str(tmp_path))
    assert backend.kernel_cache_dir() == tmp_path
    monkeypatch.delenv("TI_OFFLINE_CACHE_FILE_PATH")
    assert backend.kernel_cache_dir().parts[-3:] == (".cache", "taichi", "ticache")
