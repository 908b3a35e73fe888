"""Scenes whose keys are each valid but which cannot work together (issue 33 item 7), refused
on load with ``file: key: reason`` instead of running to a silent wrong result:

- a fill or factory region wholly behind a plane wall (no particle can live there): blamed on
  the wall's normal when the domain's centre lies behind it too (a flipped normal), else on the
  region;
- a results or recording path that cannot be written (``output_path_problem``, used by the
  command line on the path it will actually write).

An output interval longer than ``end_time`` is valid (CONTRACT.md: a benchmark wants no
samples; the run's closing sample records its end).

Where results go (issue 43, "files stay where the user put the run"): ``resolve_output_path``
is the one place an output path is turned into the file written. A scene's ``[output] h5`` and
``rrd`` resolve against the scene file's folder (``--out DIR``: their file name in DIR); a
path in a scene that is absolute, starts with ``~`` or climbs out of the scene's folder with
``..`` is refused, so a scene alone writes nothing outside its folder; a path named on the
command line (``--h5``, ``--rrd``) is the user's own choice, taken as given with ``~``
expanded. ``foreign_file_problem`` refuses to overwrite an existing file that is not a results
file, checkpoint or recording of ours.

A key an effect adds to a fill, factory, wall or body that the effect ignores where the scene
lacks its section (a temperature without heat transfer: CONTRACT.md's own example scene has
them, and a scene turns heat off by leaving out its section) is not refused but named by
``ignored_keys`` for ``check`` and ``run`` to print as notes.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import numpy as np

from ...errors import SceneError
from ..keys import effect_sections
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
    this user may not write in. ``path`` is the one the writer opens (resolve_output_path:
    ``~`` already expanded there, never here, so the check and the writer agree)."""
    if not path:
        return None
    p = Path(path)
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
    """(key, reason) for each key the scene gives but nothing will read: a key an effect adds
    to another section (scene/keys.py ``Section.adds``) that the effect ignores while the
    scene lacks its section (``Key.when_off``: a temperature without heat transfer). Read
    from the scene's objects: a key counts as given where its value is not its default."""
    out = []
    for path, section in effect_sections().items():
        if path in scene.settings:
            continue
        for host, keys in section.adds.items():
            for where, item in _host_objects(scene, host):
                for key in keys:
                    given = item.effect_values.get(key.name, key.default) != key.default
                    if key.when_off == "ignored" and given:
                        out.append((f"{where}.{key.name}", f"ignored: the scene has no [{path}] "
                                    f"section ({section.description.split(':')[0].lower()} off)"))
    return out


def _host_objects(scene, host: str) -> list:
    """(dotted key, object) of each object the scene holds of the host section ``host``."""
    if host == "materials.*":
        return [(f"materials.{name}", m) for name, m in scene.materials.items()]
    if host == "simulation":
        return [("simulation", scene.simulation)]
    items = {"walls[]": scene.walls, "bodies[]": scene.bodies, "particles[]": scene.fills,
             "factories[]": scene.factories}[host]
    return [(getattr(x, "key", None) or f"{host[:-2]}[{i}]", x) for i, x in enumerate(items)]


def _path_text_problem(text: str) -> Optional[str]:
    """Why a path string cannot name a file at all (a reason), or None."""
    if "\x00" in text:
        return "contains a NUL byte"
    if not text.strip():
        return "is empty"
    if text.endswith(("/", os.sep)) or Path(text).name in ("", ".", ".."):
        return f"{text!r} names a folder, not a file (give a file name, e.g. results.h5)"
    return None


def scene_folder(scene_path) -> Path:
    """The folder a scene's relative paths resolve against: the scene file's, or the current
    one for a scene given as text (``<string>``)."""
    source = str(scene_path)
    if source.startswith("<"):
        return Path.cwd()
    return Path(os.path.abspath(source)).parent


def resolve_output_path(scene_path, key: str, configured: Optional[str],
                        explicit: Optional[str] = None, out_dir: Optional[str] = None,
                        explicit_key: Optional[str] = None) -> Optional[str]:
    """The file (an absolute path) a results or recording path names, or None for none.

    ``explicit``: the path given on the command line (``explicit_key``, e.g. ``--h5``): the
    user's own choice, relative to the current folder, ``~`` expanded. Else ``configured``
    (the scene's ``key``, e.g. ``output.h5``): with ``out_dir`` its file name in that folder
    (``~`` in ``out_dir`` expanded), else relative to the scene's folder, which it may not
    leave: an absolute path, ``~`` or ``..`` out of the folder is refused (SceneError naming
    the scene file and key), as are a NUL byte and a name ending in a separator."""
    if explicit:
        problem = _path_text_problem(explicit)
        if problem:
            raise SceneError(str(scene_path), explicit_key or key, problem)
        return os.path.abspath(os.path.expanduser(explicit))
    if not configured:
        return None
    problem = _path_text_problem(configured)
    if problem:
        raise SceneError(str(scene_path), key, problem)
    if out_dir:
        if "\x00" in out_dir:
            raise SceneError(str(scene_path), "--out", "contains a NUL byte")
        return os.path.abspath(os.path.join(os.path.expanduser(out_dir), Path(configured).name))
    folder = scene_folder(scene_path)
    escape = None
    if configured.startswith("~"):
        escape = "starts with ~ (the home folder)"
    elif os.path.isabs(configured) or Path(configured).drive:
        escape = "is an absolute path"
    else:
        # lexically: a link the user made inside the folder (a scratch disk) is theirs
        if not Path(os.path.normpath(folder / configured)).is_relative_to(folder):
            escape = "leaves the scene's folder"
    if escape:
        flag = "--" + key.rsplit(".", 1)[-1]
        raise SceneError(str(scene_path), key,
                         f"{configured!r} {escape}: a scene's output paths stay inside its "
                         f"folder ({folder}); to write elsewhere name the file on the command "
                         f"line ({flag} FILE) or the folder (--out DIR)")
    return os.path.normpath(str(folder / configured))


# what our own files start with: HDF5's signature (results and checkpoints) and rerun's
# recording header ("RRF" and a format digit: RRF2 for rerun-sdk 0.41)
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
RERUN_MAGIC = b"RRF"


def foreign_file_problem(path, kind: str) -> Optional[str]:
    """Why the existing file ``path`` must not be overwritten by a ``kind`` ("results",
    "checkpoint", "recording") of ours (a reason), or None: it is absent, empty, or ours (an
    HDF5 file whose root attributes taichi_dem writes: ``taichi_dem_version`` and ``scene``
    for results, ``format`` "taichi_dem checkpoint ..." for checkpoints; a rerun recording's
    header). Nothing is written."""
    if not path or not os.path.isfile(path):
        return None
    try:
        with open(path, "rb") as fh:
            head = fh.read(8)
    except OSError as err:
        return f"{path} exists and cannot be read ({err.strerror or err})"
    if not head:
        return None            # an empty file holds nothing to lose
    if kind == "recording":
        if head.startswith(RERUN_MAGIC):
            return None
        return (f"{path} exists and is not a rerun recording (.rrd); refusing to overwrite it "
                "(move it away or choose another file)")
    what = "results file" if kind == "results" else "checkpoint"
    refusal = (f"{path} exists and is not a taichi_dem {what}; refusing to overwrite it (move "
               "it away or choose another file)")
    if head != HDF5_SIGNATURE:
        return refusal
    try:
        import h5py
        with h5py.File(path, "r") as f:
            attrs = f.attrs
            if kind == "results":
                ours = "taichi_dem_version" in attrs and "scene" in attrs
            else:
                found = attrs.get("format")
                ours = isinstance(found, (str, bytes)) and (
                    found.decode() if isinstance(found, bytes) else found
                ).startswith("taichi_dem checkpoint")
    except (OSError, ValueError, KeyError):
        return f"{path} exists and cannot be read as HDF5; refusing to overwrite it"
    return None if ours else refusal


class ConsistencySections:
    """Mixin of the scene parser (scene/loader.py): the checks of the module docstring."""

    def check_consistency(self, doc: dict, simulation, output, sources, walls, bodies) -> None:
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
