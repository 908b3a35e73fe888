"""Every exception a user of taichi_dem can meet, in one place.

``SceneError`` (bad input: CLI exit 2) is the only one raised before anything is built;
``DivergenceError`` (exit 3) stops a run whose state is no longer physical. ``GeometryError``
belongs to the standalone ``geometry`` package (plain numpy and trimesh) and is re-exported
here; the loader turns it into a ``SceneError`` naming the scene file and key.
"""
from taichi_dem.geometry.mesh import GeometryError

__all__ = ["SceneError", "GeometryError", "BackendError", "DivergenceError",
           "StaleSimulationError", "CheckpointError", "WindowError"]


class SceneError(Exception):
    """Bad input: names the file, the key (dotted TOML path) and the reason.

    The CLI prints ``str(err)`` as one paragraph and exits with status 2.
    """

    def __init__(self, file: str, key: str, reason: str):
        self.file, self.key, self.reason = str(file), key, reason
        super().__init__(f"{self.file}: {key}: {reason}" if key else f"{self.file}: {reason}")


class BackendError(RuntimeError):
    """The Taichi runtime cannot be had as asked (an unknown arch)."""


class DivergenceError(RuntimeError):
    """The simulation blew up (non-finite state); the message says when and the likely fix.

    Raised at an output sample; ``err.checkpoint`` names the file holding the last good state
    ("" when none was written)."""


class StaleSimulationError(RuntimeError):
    """The simulation was closed, or its Taichi runtime was re-initialised by another one."""


class CheckpointError(RuntimeError):
    """A checkpoint file that cannot be read or does not fit this version of the engine."""


class WindowError(RuntimeError):
    """The window cannot be opened here (no display, no Vulkan)."""


class ResultsFileError(Exception):
    """A results file that cannot be read as one (``taichi-dem plot``): missing, not HDF5, a
    checkpoint, or without /series/time. The message names the file and the reason."""
