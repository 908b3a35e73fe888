"""Scenes whose keys are each valid but which cannot work together (issue 33 item 7), refused
on load with ``file: key: reason`` instead of running to a silent wrong result:

- an output interval longer than ``end_time`` (a command-line run would record nothing after
  its start: ``interval_problem``, used by ``check`` and ``run``; a Python script may run past
  end_time, so the loader does not refuse it);
- a fill or factory region wholly behind a plane wall (no particle can live there): blamed on
  the wall's normal when the domain's centre lies behind it too (a flipped normal), else on the
  region;
- a results or recording path that cannot be written (``output_path_problem``, used by the
  command line on the path it will actually write).

A temperature on a fill, factory, wall or body in a scene without ``[thermal]`` is not refused
(CONTRACT.md's own example scene has them: a scene turns heat off by leaving out [thermal]) but
named by ``ignored_keys`` for ``check`` and ``run`` to print as notes.
"""
from __future__ import annotations

import os
import tomllib
from pathlib import Path
from typing import Optional

import numpy as np

from .particles import region_bounds


def region_corners(region) -> Optional[np.ndarray]:
    """The 8 corners (m) of the axis-aligned box around a region (particles.region_bounds);
    None for no region."""
    if region is None:
        return None
    lo, hi = region_bounds(region)
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def output_path_problem(path) -> Optional[str]:
    """Why the file ``path`` cannot be written (None when it can, as far as the file system
    tells before trying): a folder in its place, a file where a folder must be, or a folder
    this user may not write in."""
    if not path:
        return None
    p = Path(path).expanduser()
    if p.is_dir():
        return f"{path} is a folder, not a file"
    if p.exists():
        return None if os.access(p, os.W_OK) else f"{path} exists and is not writable"
    parent = p.parent if str(p.parent) else Path(".")
    while not parent.exists():
        if parent.parent == parent:
            break
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        return f"{parent} is a file, not a folder: {path} cannot be created under it"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"the folder {parent} is not writable"
    return None


def ignored_keys(scene) -> list[tuple[str, str]]:
    """(key, reason) for each key the scene gives but nothing will read: temperatures without
    [thermal]."""
    if scene.thermal is not None:
        return []
    out = []
    for f in tuple(scene.fills) + tuple(scene.factories):
        if f.temperature is not None:
            out.append((f"{f.key}.temperature", "ignored: the scene has no [thermal] section "
                        "(heat transfer off)"))
    for kind, items in (("walls", scene.walls), ("bodies", scene.bodies)):
        for i, item in enumerate(items):
            if getattr(item, "temperature", None) is not None:
                out.append((f"{kind}[{i}].temperature", "ignored: the scene has no [thermal] "
                            "section (heat transfer off)"))
    return out


def interval_problem(scene) -> Optional[tuple[str, str]]:
    """(key, reason) when the scene gives an output interval longer than its end_time."""
    given = "interval" in (tomllib.loads(scene.text).get("output", {}) if scene.text else {})
    if given and scene.output.interval > scene.simulation.end_time:
        return ("output.interval",
                f"{scene.output.interval:g} s is longer than simulation.end_time "
                f"{scene.simulation.end_time:g} s: the run would record no sample after its "
                "start (shorten the interval or lengthen the run)")
    return None


class ConsistencySections:
    """Mixin of the scene parser (scene/loader.py): the checks of the module docstring."""

    def check_consistency(self, doc: dict, simulation, output, sources, walls, bodies,
                          thermal) -> None:
        """Refuse the combinations of the module docstring (``doc``: the raw scene, to tell a
        key given from its default)."""
        centre = 0.5 * (np.asarray(self.domain.min, float) + np.asarray(self.domain.max, float))
        for f in sources:
            corners = region_corners(getattr(f, "region", None))
            if corners is None:
                continue
            for i, w in enumerate(walls):
                n = np.asarray(w.normal, float)
                p = np.asarray(w.point, float)
                if np.max((corners - p) @ n) >= 0.0:
                    continue
                if (centre - p) @ n < 0.0:
                    raise self.err(f"walls[{i}].normal",
                                   f"points away from the domain's centre, and the region of "
                                   f"{f.key} lies wholly behind wall '{w.name}': particles live "
                                   "on the side the normal points to (flip it)")
                raise self.err(f"{f.key}.region",
                               f"lies wholly behind wall '{w.name}' (walls[{i}]), on the side "
                               "its normal points away from: no particle can be placed there")
