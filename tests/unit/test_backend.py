"""The kernel cache's lock: a leftover of a killed process is removed, a live one is not;
Taichi's IR optimisation level."""
import os
import time
from pathlib import Path

import pytest

import taichi_dem
from taichi_dem.engine import backend


def test_a_stale_kernel_cache_lock_is_removed_with_a_note(tmp_path, capsys):
    lock = tmp_path / "ticache.lock"
    lock.write_bytes(b"")
    # a lock older than a writer ever holds one (the threshold, which a suite-long watch of
    # the lock says is ample: held 0.1 s at most)
    assert backend.STALE_CACHE_LOCK_SECONDS <= 30.0
    old = time.time() - backend.STALE_CACHE_LOCK_SECONDS - 1.0
    os.utime(lock, (old, old))
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


KERNEL_WITH_A_TYPO = '''
import taichi as ti
from taichi_dem.engine import frontend
print("applied", frontend.apply())
ti.init(arch=ti.cpu, log_level=ti.WARN, offline_cache=False)
x = ti.field(float, 4)

@ti.kernel
def fill():
    for i in x:
        x[i] = undefined_name + 1.0

@ti.kernel
def double():
    for i in x:
        x[i] = 2.0 * i

double()
double()
print("values", x.to_numpy().tolist())


@ti.data_oriented
class Tripler:
    def __init__(self):
        self.y = ti.field(float, 3)

    @ti.kernel
    def fill(self):
        for i in self.y:
            self.y[i] = 3.0 * i


tripler = Tripler()
tripler.fill()
print("method", tripler.y.to_numpy().tolist())
try:
    fill()
except Exception as err:
    print(type(err).__name__)
    print(err)
'''


def test_the_front_end_savings_keep_taichis_kernels_and_error_positions(tmp_path):
    """engine/frontend.py: with the savings a kernel compiles and runs as before, and a compile
    error still names the file, the line and the expression (in a child process: ti.init
    here would invalidate the fields of this worker's other simulations)."""
    import subprocess
    import sys
    script = tmp_path / "typo.py"
    script.write_text(KERNEL_WITH_A_TYPO)
    env = dict(__import__("os").environ, TAICHI_DEM_CACHE=str(tmp_path / "cache"))

    def run():
        return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                              timeout=120, check=False, env=env).stdout
    first = run()
    assert list((tmp_path / "cache" / "memo" / "sources").glob("*.pkl"))
    out = run()                 # the functions' sources now read from the disk
    assert out == first
    assert "applied True" in out
    assert "values [0.0, 2.0, 4.0, 6.0]" in out
    # a kernel in a class body is still told from one in a function (_quick_class_test)
    assert "method [0.0, 3.0, 6.0]" in out
    assert "TaichiNameError" in out
    assert f'File "{script}", line 11, in fill:' in out, out
    assert "        x[i] = undefined_name + 1.0\n               ^^^^^^^^^^^^^^\n" in out
    # the file edited (same length): the kernel's new source is read, not the kept one
    script.write_text(KERNEL_WITH_A_TYPO.replace("2.0 * i", "5.0 * i"))
    assert "values [0.0, 5.0, 10.0, 15.0]" in run()


def test_the_ir_optimisation_level(monkeypatch):
    """Off (0) on a CPU unless $TAICHI_DEM_OPT_LEVEL says 1; Taichi's default (1) on a GPU;
    anything else in the variable is refused with its name."""
    from taichi_dem.errors import BackendError
    monkeypatch.delenv("TAICHI_DEM_OPT_LEVEL", raising=False)
    assert backend.ir_optimisation_level("cpu") == 0
    assert backend.ir_optimisation_level("cuda") == 1
    monkeypatch.setenv("TAICHI_DEM_OPT_LEVEL", "1")
    assert backend.ir_optimisation_level("cpu") == 1
    monkeypatch.setenv("TAICHI_DEM_OPT_LEVEL", "fast")
    with pytest.raises(BackendError, match="TAICHI_DEM_OPT_LEVEL"):
        backend.ir_optimisation_level("cpu")


def test_the_runtime_runs_at_that_level():
    import taichi as ti
    from tests.conftest import SMALL_SCENE
    with taichi_dem.Simulation.from_text(SMALL_SCENE.format(precision="f64", rolling=0.0,
                                                             count=10)) as sim:
        sim.step(2)
        assert ti.lang.impl.current_cfg().opt_level == backend.ir_optimisation_level("cpu")


def test_a_bad_level_is_a_clear_error_from_the_command_line(tmp_path):
    """Exit status 2 and one line naming the variable, no traceback."""
    import subprocess
    import sys
    from pathlib import Path
    scene = Path(__file__).resolve().parents[2] / "demos" / "pile.toml"
    out = subprocess.run([sys.executable, "-m", "taichi_dem", "run", str(scene), "--until",
                          "0.001", "--out", str(tmp_path)],
                         env=dict(os.environ, TAICHI_DEM_OPT_LEVEL="fast"),
                         capture_output=True, text=True)
    assert out.returncode == 2
    assert "TAICHI_DEM_OPT_LEVEL='fast'" in out.stderr and "Traceback" not in out.stderr


@pytest.mark.parametrize("plain", ["0", "1"])
def test_import_hook_patches_taichi_while_it_loads(plain, tmp_path):
    """``import taichi_dem`` before Taichi: Taichi's class-body test and its fields'
    declaration trace are the quick ones (_taichi_hooks.py) from Taichi's own import on; a
    kernel in a ``ti.data_oriented`` class still compiles as a method; the trace lists the
    same frames as traceback.extract_stack. With TAICHI_DEM_PLAIN_TAICHI=1 Taichi is left as
    it is."""
    import os
    import subprocess
    import sys
    code = """
import taichi_dem
import taichi as ti
from taichi.lang import kernel_impl, util
from taichi_dem import _taichi_hooks as h
print(kernel_impl._inside_class is h.inside_class, util.get_traceback is h.declaration_trace)
ti.init(arch=ti.cpu, offline_cache=False)

@ti.data_oriented
class Holder:
    def __init__(self):
        self.x = ti.field(ti.i32, 3)

    @ti.kernel
    def fill(self, v: ti.i32):
        for i in range(3):
            self.x[i] = v

h2 = Holder()
h2.fill(7)
print(int(h2.x.to_numpy().sum()))
import re, traceback
def frames():
    quick, full = util.get_traceback(0), traceback.extract_stack()
    listed = re.findall(r'File "(.*)", line (\\d+), in (\\S+)', quick)
    return listed == [(x.filename, str(x.lineno), x.name) for x in full]
print(frames())
"""
    env = dict(os.environ, TAICHI_DEM_PLAIN_TAICHI=plain)
    script = tmp_path / "hooked.py"          # (Taichi reads the kernels' source from a file)
    script.write_text(code)
    env["TAICHI_DEM_CACHE"] = str(tmp_path / "memo")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env,
                         cwd=str(Path(__file__).resolve().parents[2]), timeout=300)
    assert out.returncode == 0, out.stderr
    lines = [x for x in out.stdout.splitlines() if not x.startswith("[Taichi]")]
    patched = "False False" if plain == "1" else "True True"
    assert lines == [patched, "21", "True"]

