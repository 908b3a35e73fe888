"""What the fuzz tests share: ``check`` (and a scene refused on load) must not start the
Taichi runtime, or a malformed scene would cost a compile before its error."""
import pytest


class RuntimeStarted(BaseException):
    """``check`` (or a scene refused on load) must not initialise Taichi."""


@pytest.fixture
def no_taichi_runtime(monkeypatch):
    """Starting the Taichi runtime (engine/backend.py ``acquire``) raises RuntimeStarted."""
    from taichi_dem.engine import backend

    def refuse(*args, **kwargs):
        raise RuntimeStarted("the Taichi runtime was started (ti.init): kernels would compile")
    monkeypatch.setattr(backend, "acquire", refuse)
