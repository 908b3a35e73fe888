#!/usr/bin/env python3
"""Set-up and everyday tasks with nothing but python3 (stdlib only).

    python3 tasks.py demo    create .venv, install taichi_dem, run the main demo
    python3 tasks.py test    create .venv, install taichi_dem with test extras, run the tests
    python3 tasks.py docs    create .venv, install with test and docs extras, build the
                             documentation into docs/_build/html (warnings are errors; the
                             pages' executed examples run during the build)
    python3 tasks.py setup   only create .venv and install
"""
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
PY = VENV / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
MAIN_DEMO = "paddle_cooler"


def run(*cmd):
    print("+", " ".join(str(c) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True, cwd=ROOT)


STAMP = VENV / "taichi-dem-setup.txt"


def _setup_key() -> str:
    """What an installed .venv was set up from: the project file's contents."""
    import hashlib
    return hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()


def setup(extras: str = "test"):
    """Create .venv and install taichi_dem (editable) with ``extras``; nothing to do when the
    .venv was set up from the same pyproject.toml with these extras or more (the stamp),
    which saves a pip run of ~6-12 s per task (`.ci/run` runs two tasks)."""
    wanted = set(extras.split(","))
    if PY.exists() and STAMP.exists():
        key, _, had = STAMP.read_text().partition("\n")
        if key == _setup_key() and wanted <= set(had.split()):
            print(f"+ .venv is set up ({', '.join(sorted(had.split()))}; {STAMP.name})",
                  flush=True)
            return
    if not PY.exists():
        venv.create(VENV, with_pip=True)
        run(PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip")
    STAMP.unlink(missing_ok=True)
    run(PY, "-m", "pip", "install", "--quiet", "-e", f".[{extras}]")
    STAMP.write_text(f"{_setup_key()}\n{' '.join(sorted(wanted))}\n")


def main(argv):
    task = argv[1] if len(argv) > 1 else "test"
    try:
        if task == "setup":
            setup()
        elif task == "demo":
            setup()
            run(PY, "-m", "taichi_dem", "demo", MAIN_DEMO, *argv[2:])
        elif task == "test":
            setup()
            # one pytest worker per core, each test file kept on one worker (module fixtures
            # run once): the suite is bound by Taichi's single-threaded JIT compilation
            # (~4 s per new simulation with a cold kernel cache), which one worker leaves
            # on one core. Two workers fill both cores, so a simulation's own worker threads
            # (engine/stepper.py, spin barriers) would wait for cores: the tests run the
            # parallel mode's launches (the same results bit for bit) except where
            # tests/unit/test_loop_mode.py asks for the threads
            os.environ.setdefault("TAICHI_DEM_WORKERS", "0")
            # --no-loadscope-reorder: hand the files out in the collection order, which
            # tests/conftest.py makes slowest first (xdist's default goes by test count)
            run(PY, "-m", "pytest", "-q", "-n", "auto", "--dist", "loadfile",
                "--no-loadscope-reorder", *argv[2:])
        elif task == "docs":
            setup("test,docs")
            # the reference pages are generated and the {exec-python} examples run while
            # Sphinx reads the pages (docs/_ext/); -W: a warning (a broken link, a page in no
            # table of contents, an example that raises) fails the build
            os.environ.setdefault("TI_OFFLINE_CACHE_FILE_PATH",
                                  str(ROOT / "docs" / "_build" / "ticache"))
            run(PY, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "docs",
                "docs/_build/html", *argv[2:])
        else:
            print(__doc__)
            return 2
    except subprocess.CalledProcessError as err:
        return err.returncode or 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
