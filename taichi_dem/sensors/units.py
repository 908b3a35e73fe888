"""The unit of every /series name: the sensors' declarations (sensors/series.py) and the
effects' (``SERIES`` in their settings modules, scene/catalog.py). Plain Python."""
from __future__ import annotations

import fnmatch

from ..scene import catalog
from .series import SERIES, Series


def declared() -> tuple[Series, ...]:
    """The sensors' series and every effect's (their settings modules' SERIES)."""
    out = list(SERIES)
    for module in catalog.settings_modules():
        out.extend(getattr(module, "SERIES", ()))
    return tuple(out)


def declaration(name: str) -> Series | None:
    """The declared Series the name ``name`` (relative to /series) matches, or None."""
    parts = name.split("/")
    for s in declared():
        pattern = s.name.split("/")
        if len(pattern) == len(parts) and all(fnmatch.fnmatchcase(p, q)
                                              for p, q in zip(parts, pattern)):
            return s
    return None


def unit_of(name: str) -> str | None:
    """The unit of the series ``name``, or None when undeclared."""
    d = declaration(name)
    return d.unit if d is not None else None


def describe(name: str) -> str | None:
    """The description of the series ``name``, or None when undeclared."""
    d = declaration(name)
    return d.description if d is not None else None
