"""Mesh geometry for taichi_dem: plain numpy and trimesh, no Taichi.

``TriMesh`` (vertices in m, int64 faces, per-face ``two_sided`` flags) is what every builder
and the importer return; ``build(name, params, key=...)`` serves a scene's
``mesh = { builder = "...", ... }``, ``build_mesh(spec)`` also takes ``{ file = ... }`` or a
list of meshes merged into one body; ``describe_builders()`` is the table printed by
``taichi-dem check --builders``. Conventions (normals towards the particle side, thin plates
single-layer and two-sided) are in :mod:`geometry.mesh`.
"""
from .mesh import GeometryError, TriMesh
from .builders import (BUILDERS, Builder, Param, body_axis, build, build_mesh, default_segments,
                       describe_builders, helicoid_area, load_mesh)

__all__ = ["TriMesh", "GeometryError", "build", "build_mesh", "BUILDERS", "Builder", "Param",
           "describe_builders", "load_mesh", "body_axis", "helicoid_area", "default_segments"]
