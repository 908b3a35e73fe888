"""taichi_dem: discrete element method with Taichi, for drums, dryers and coolers."""
from ._version import __version__

_ERRORS = ("SceneError", "GeometryError", "BackendError", "DivergenceError",
           "StaleSimulationError", "CheckpointError", "WindowError")


__all__ = ["__version__", "Simulation", *_ERRORS]


def __dir__():
    return sorted(set(globals()) | set(__all__))


def __getattr__(name):
    # keep `import taichi_dem` light: Taichi is imported only when a simulation is made
    if name == "Simulation":
        from .run.simulation import Simulation
        return Simulation
    if name in _ERRORS:
        from . import errors
        return getattr(errors, name)
    raise AttributeError(name)
