"""taichi_dem: discrete element method with Taichi, for drums, dryers and coolers."""
__version__ = "0.1.0"


def __getattr__(name):
    # keep `import taichi_dem` light: Taichi is imported only when a simulation is made
    if name == "Simulation":
        from .run.simulation import Simulation
        return Simulation
    if name in ("SceneError",):
        from .scene.model import SceneError
        return SceneError
    raise AttributeError(name)
