"""Mesh import through trimesh (STL, OBJ, PLY, OFF, glTF), with units, scale and checks.

The ``file`` builder and ``load_mesh`` (builders.py) call ``read_mesh``; it calls nothing back."""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from .mesh import MAX_EXTENT, MIN_EXTENT, TriMesh
from .mesh import ParameterError as _Bad

UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254, "ft": 0.3048, "um": 1e-6}


def read_mesh(file: str, *, scale: float, units: str, repair: bool, flip_normals: bool,
              two_sided: Optional[bool], base_dir=None) -> TriMesh:
    """The ``file`` builder's body: errors are raised about the parameter at fault."""
    import trimesh

    path = Path(file).expanduser()
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    if path.is_dir():
        raise _Bad("file", f"{path} is a directory, not a mesh file")
    if not path.is_file():
        raise _Bad("file", f"no such file: {path}")
    try:
        with np.errstate(all="ignore"):
            loaded = trimesh.load(str(path), force="mesh", process=False)
    except ImportError:         # trimesh guessing the text encoding of binary junk
        raise _Bad("file", f"cannot read {path} as a mesh: the file is corrupt or not a "
                           f"{path.suffix or 'mesh'} file") from None
    except IndexError as e:
        raise _Bad("file", f"cannot read {path} as a mesh: a face refers to a vertex the "
                           f"file does not have ({e})") from None
    except Exception as e:      # trimesh raises many types for unreadable files
        raise _Bad("file", f"cannot read {path} as a mesh: {e}") from None
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64)
    if len(faces) == 0:
        raise _Bad("file", f"{path} holds no triangles")
    if not np.all(np.isfinite(vertices[np.unique(faces)])):
        if not repair:
            bad = int((~np.all(np.isfinite(vertices), axis=1)).sum())
            raise _Bad("file", f"{path}: {bad} vertices are not finite (NaN or inf); "
                               "repair = true drops their triangles")
        ok = np.all(np.isfinite(vertices), axis=1)
        faces = faces[np.all(ok[faces], axis=1)]
    factor = UNITS[units] * scale
    with np.errstate(all="ignore"):  # absurd coordinates are refused below, without warnings
        mesh = trimesh.Trimesh(vertices * factor, faces, process=False)
        mesh.merge_vertices()        # STL stores each triangle's corners separately
    if repair:
        extent = float(np.linalg.norm(mesh.extents)) if len(mesh.faces) else 1.0
        mesh.update_faces(mesh.nondegenerate_faces(height=1e-9 * extent))
        mesh.update_faces(mesh.unique_faces())
        mesh.remove_unreferenced_vertices()
        if len(mesh.faces) == 0:
            raise _Bad("file", f"{path}: no usable triangles left after repair")
    size = float(np.max(np.ptp(mesh.vertices[np.unique(mesh.faces)], axis=0)))
    if size > MAX_EXTENT or size < MIN_EXTENT:
        raw = size / factor
        fits = sorted((abs(np.log10(raw * f * scale)), u) for u, f in UNITS.items()
                      if 1e-3 <= raw * f * scale <= 100.0)
        hint = f"; with units = \"{fits[0][1]}\" it would be " \
               f"{raw * UNITS[fits[0][1]] * scale:.4g} m" if fits else ""
        raise _Bad("units", f"{path} is {size:.4g} m across after units = \"{units}\" and "
                            f"scale = {scale:g}: absurd for a DEM scene (wrong units?){hint}")
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if flip_normals:
        faces = faces[:, ::-1]
    out = TriMesh(np.asarray(mesh.vertices), faces)
    if two_sided is None:
        two_sided = out.open_edge_count() > 0
    return out.with_two_sided(two_sided)
