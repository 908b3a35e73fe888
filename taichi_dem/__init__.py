"""taichi_dem: discrete element method with Taichi, for drums, dryers and coolers."""
from pathlib import Path as _Path

from ._version import __version__


def _checkout_folders() -> None:
    """A source checkout on PYTHONPATH without an install (the device scripts): let
    taichi_dem.thermal, .geometry and .demos resolve to the checkout's top-level folders, as the
    installed layout maps them (pyproject.toml's package-dir). Only when the folder above is this
    project's checkout, so another project's `thermal` in site-packages is never picked up."""
    root = _Path(__file__).resolve().parent.parent
    pyproject = root / "pyproject.toml"
    if (root / "thermal" / "__init__.py").exists() and pyproject.exists() \
            and 'name = "taichi-dem"' in pyproject.read_text():
        __path__.append(str(root))


_checkout_folders()


def _hook_taichi() -> None:
    # two of the front end's savings, applied while Taichi is imported (_taichi_hooks.py)
    from ._taichi_hooks import install
    install()


_hook_taichi()

_ERRORS = ("SceneError", "GeometryError", "BackendError", "DivergenceError",
           "StaleSimulationError", "CheckpointError", "WindowError")


__all__ = ["__version__", "Simulation", *_ERRORS]


def __dir__():
    return sorted(n for n in set(globals()) | set(__all__) if not n.startswith("_") or n == "__version__")


def __getattr__(name):
    # keep `import taichi_dem` light: Taichi is imported only when a simulation is made
    if name == "Simulation":
        from .run.simulation import Simulation
        return Simulation
    if name in _ERRORS:
        from . import errors
        return getattr(errors, name)
    raise AttributeError(name)
