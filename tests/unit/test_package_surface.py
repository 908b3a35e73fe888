"""The package's own surface (issue 33 item 2, in part): a version on the command line, the
public names listed, Taichi's import banner kept off the stdout of report commands, a LICENSE."""
import subprocess
import sys
from pathlib import Path

import taichi_dem
from taichi_dem.app.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_version_on_the_command_line(capsys):
    try:
        main(["--version"])
    except SystemExit as stop:
        assert stop.code == 0
    assert capsys.readouterr().out.strip() == f"taichi-dem {taichi_dem.__version__}"


def test_the_public_names_are_listed_and_reachable():
    assert {"Simulation", "SceneError", "__version__"} <= set(taichi_dem.__all__)
    assert set(taichi_dem.__all__) <= set(dir(taichi_dem))
    for name in taichi_dem.__all__:
        assert getattr(taichi_dem, name) is not None


def test_check_prints_no_taichi_banner_on_stdout():
    """`check` describes the effects (which imports Taichi): its stdout is the report alone."""
    out = subprocess.run([sys.executable, "-m", "taichi_dem", "check",
                          str(ROOT / "demos" / "pile.toml")], capture_output=True, text=True,
                         cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("scene: ") and "[Taichi]" not in out.stdout


def test_the_license_the_metadata_names_is_in_the_repository():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("Apache License\nVersion 2.0")
    assert 'license = "Apache-2.0"' in (ROOT / "pyproject.toml").read_text()
