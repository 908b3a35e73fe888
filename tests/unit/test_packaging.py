"""The package as a user installs it: one namespace (taichi_dem.thermal, taichi_dem.geometry,
taichi_dem.demos map the checkout's top-level folders, no top-level `thermal` or `geometry`),
setup.py's package list complete, and a wheel installed outside the checkout running a demo
from its own package data."""
import ast
import os
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
MAPPED = PYPROJECT["tool"]["setuptools"]["package-dir"]


def _installed_name(folder: Path) -> str:
    """The dotted name a source folder installs as (taichi_dem/..., or a mapped top-level one)."""
    rel = folder.relative_to(ROOT).parts
    for name, src in MAPPED.items():
        if rel[0] == src:
            return ".".join((name, *rel[1:]))
    return ".".join(rel)


def test_every_package_folder_is_found():
    """setup.py finds the packages (no list kept by hand): every folder with an __init__.py
    under taichi_dem/ and the mapped top-level folders, the mapped folders' data-only
    subfolders (namespace packages, so setuptools does not warn they are missing), and nothing
    else."""
    import runpy
    found_by_setup = set(runpy.run_path(str(ROOT / "setup.py"))["packages"]())
    folders = [p.parent for top in ("taichi_dem", *MAPPED.values())
               for p in (ROOT / top).rglob("__init__.py")]
    data_folders = [p for top in MAPPED.values() for p in (ROOT / top).rglob("*")
                    if p.is_dir() and "__pycache__" not in p.parts
                    and not (p / "__init__.py").exists()]
    found = {_installed_name(f) for f in folders + data_folders}
    assert found == found_by_setup
    assert "taichi_dem.demos.dryers" in found_by_setup
    assert {"taichi_dem.effects.drag", "taichi_dem.thermal", "taichi_dem.demos"} <= found_by_setup
    assert "packages" not in PYPROJECT["tool"]["setuptools"], "the list is setup.py's to find"


def test_no_top_level_thermal_or_geometry_imports():
    """`import thermal` would load a second copy of the module under another name (or another
    project's package of that name): every import goes through taichi_dem."""
    bad = []
    for path in ROOT.rglob("*.py"):
        if ".venv" in path.parts or "build" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0
                     else [])
            bad += [f"{path.relative_to(ROOT)}:{node.lineno} {n}" for n in names
                    if n.split(".")[0] in ("thermal", "geometry")]
    assert bad == []


def test_namespace_and_dir():
    import taichi_dem
    from taichi_dem import geometry, thermal
    assert Path(thermal.__file__).parent == ROOT / "thermal"
    assert Path(geometry.__file__).parent == ROOT / "geometry"
    assert {"Simulation", "SceneError", "__version__"} <= set(dir(taichi_dem))
    assert not [n for n in dir(taichi_dem) if n.startswith("_") and n != "__version__"]


@pytest.mark.slow
def test_wheel_outside_the_checkout_runs_a_demo(tmp_path):
    """Build the wheel, install it (without dependencies: the test's environment has them) into
    a folder outside the checkout and run `taichi-dem demo pile` from there for a few steps."""
    dist = tmp_path / "dist"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w",
                            str(dist), str(ROOT)], capture_output=True, text=True)
    if build.returncode != 0 and "No matching distribution" in build.stderr:
        pytest.skip("the build backend could not be fetched: " + build.stderr.strip()[-200:])
    assert build.returncode == 0, build.stderr
    (wheel,) = dist.glob("taichi_dem-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {"taichi_dem", wheel.name.split("-py3")[0] + ".dist-info"}
    assert "taichi_dem/demos/pile.toml" in names
    # every scene, map and calibration spec the demos and the docs' commands use travels with
    # it (the calibration specs were left out once: `taichi-dem calibrate`'s example needs them)
    shipped = {p.relative_to(ROOT / "demos").as_posix() for p in (ROOT / "demos").rglob("*")
               if p.is_file() and p.suffix in (".toml", ".json", ".csv", ".stl", ".py")
               and not {"out", "__pycache__"} & set(p.relative_to(ROOT / "demos").parts)}
    assert "calibration/fly_ash_seed001.toml" in shipped
    missing = sorted(f for f in shipped if f"taichi_dem/demos/{f}" not in names)
    assert not missing, missing
    assert any(n.endswith("licenses/LICENSE") for n in names)
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target",
                    str(site), str(wheel)], check=True)
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = dict(os.environ, PYTHONPATH=str(site), TAICHI_DEM_WORKERS="0")
    where = subprocess.run([sys.executable, "-c", "import taichi_dem.thermal.correlations as c, "
                            "taichi_dem.app.demos as d; print(c.__file__); print(d.DEMOS_DIR)"],
                           cwd=work, env=env, capture_output=True, text=True, check=True)
    assert all(line.startswith(str(site)) for line in where.stdout.split()), where.stdout
    run = subprocess.run([sys.executable, "-m", "taichi_dem", "demo", "pile", "--until", "0.02",
                          "--no-plots", "--quiet", "--out", "o"],
                         cwd=work, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (work / "o" / "pile.h5").exists() and (work / "o" / "pile.xdmf").exists()
    # the tutorials' scenes come with the wheel: a copy to edit, which checks
    assert "taichi_dem/demos/tutorials/first_drum.toml" in names
    copy = subprocess.run([sys.executable, "-m", "taichi_dem", "demo", "hot_cooler", "--copy", "."],
                          cwd=work, env=env, capture_output=True, text=True, timeout=120)
    assert copy.returncode == 0 and (work / "hot_cooler.toml").exists(), copy.stderr
    check = subprocess.run([sys.executable, "-m", "taichi_dem", "check", "hot_cooler.toml"],
                           cwd=work, env=env, capture_output=True, text=True, timeout=300)
    assert check.returncode == 0, check.stderr[-2000:]
