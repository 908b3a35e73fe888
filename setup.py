"""The package list, found rather than kept by hand: every package under taichi_dem/, and
the top-level folders pyproject.toml maps into the namespace (thermal/, geometry/, demos/ as
taichi_dem.thermal, ...). Everything else is declared in pyproject.toml."""
import tomllib
from pathlib import Path

from setuptools import find_namespace_packages, find_packages, setup

ROOT = Path(__file__).resolve().parent


def packages() -> list[str]:
    """The dotted names of every package the wheel holds."""
    mapped = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    found = find_packages(where=str(ROOT), include=["taichi_dem", "taichi_dem.*"])
    for name, folder in mapped.items():
        # Namespace packages too: the demos' data-only folders (calibration/, dryers/, ...) are
        # packages to setuptools, and leaving them out draws its "absent from packages" warning.
        inner = find_namespace_packages(where=str(ROOT / folder), exclude=["*__pycache__*"])
        found += [name] + [f"{name}.{p}" for p in inner]
    return sorted(found)


if __name__ == "__main__":
    setup(packages=packages())
