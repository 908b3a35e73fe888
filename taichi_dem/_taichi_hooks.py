"""Two of engine/frontend.py's savings in Taichi 1.7's Python side, installed *while Taichi is
imported* (``import taichi`` itself defines ~100 kernels and functions, and creates fields
later on the same path), so that they also cover Taichi's own definitions at import:

- ``kernel_impl._inside_class``: whether ``@ti.kernel`` / ``@ti.func`` decorates a method in a
  class body, which Taichi answers by reading the calling frame's source line
  (``inspect.getframeinfo``, ~0.3 ms each: ~40 ms of ``import taichi``); here from the frame's
  namespace (``inside_class``);
- ``util.get_traceback``: the declaration trace Taichi keeps with every field and SNode for
  its error messages (and prints under its warnings), made by ``traceback.extract_stack``
  (which reads each frame's source line, ~0.05 ms a field, ~700 fields per simulation); here
  the same frames as ``File "...", line N, in f`` lines, without the source lines
  (``declaration_trace``; tests/unit/test_backend.py compares the frames).

``install()`` (called by taichi_dem/__init__.py, before anything imports Taichi) adds an import
hook that applies both as Taichi's modules are executed; engine/frontend.py applies them again
(no harm) for a Taichi imported before taichi_dem. Only Taichi 1.7.x, and not with
``TAICHI_DEM_PLAIN_TAICHI=1``. Nothing here imports Taichi.
"""
import os
import sys

_HOOKED = {"taichi.lang.kernel_impl", "taichi.lang.util"}


def inside_class(level_of_class_stackframe):
    """Whether the frame at this depth is running a ``class`` statement (Taichi's question):
    the frame just below it is then the class body, whose namespace Python gives
    ``__module__`` and ``__qualname__`` before the body runs."""
    try:
        names = sys._getframe(level_of_class_stackframe - 1).f_locals
    except ValueError:           # (no frame that deep)
        return False
    return "__module__" in names and "__qualname__" in names


def declaration_trace(stacklevel=1):
    """The calling frames, outermost first, as Taichi's ``get_traceback`` lists them (less the
    ``stacklevel`` innermost callers), without their source lines."""
    try:
        frame = sys._getframe(1 + stacklevel)
    except ValueError:
        return ""
    lines = []
    while frame is not None:
        code = frame.f_code
        lines.append(f'  File "{code.co_filename}", line {frame.f_lineno}, in {code.co_name}\n')
        frame = frame.f_back
    return "".join(reversed(lines))


def plain_taichi() -> bool:
    """The savings are switched off (``TAICHI_DEM_PLAIN_TAICHI=1``)."""
    return os.environ.get("TAICHI_DEM_PLAIN_TAICHI", "") not in ("", "0")


def _patch(module) -> None:
    from taichi._lib import core
    if (core.get_version_major(), core.get_version_minor()) != (1, 7):
        return
    if module.__name__ == "taichi.lang.kernel_impl":
        module._inside_class = inside_class
    elif module.__name__ == "taichi.lang.util":
        module.get_traceback = declaration_trace


class _Finder:
    """A meta-path finder that patches Taichi's modules in ``_HOOKED`` right after they run
    (before the modules that import names from them, and before Taichi's own kernels)."""

    def find_spec(self, name, path, target=None):
        if name not in _HOOKED:
            return None
        from importlib.machinery import PathFinder
        spec = PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            try:
                _patch(module)
            except Exception:        # an unexpected Taichi: leave it as it is
                pass
        spec.loader.exec_module = exec_module
        return spec


def install() -> None:
    """Hook Taichi's import (once; nothing when Taichi is imported already or the savings are
    off)."""
    if plain_taichi() or "taichi" in sys.modules:
        return
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
