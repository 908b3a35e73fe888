"""An XDMF 3 file beside a results file, so that ParaView (or VisIt) opens the particle frames
as a time series of points (issue 33 item 4): written when a run's recorder closes, and by
``taichi-dem export RESULTS.h5 --xdmf``.

The XDMF file holds no data: it describes each /frames/<k> group of the HDF5 file as a grid of
N points (Polyvertex topology, the ``position`` dataset as XYZ geometry) at the frame's time,
with every other per-particle dataset as a point attribute (scalars: temperature, radius, mass,
moisture, material, id; 3-vectors: velocity, angular_velocity), named with its unit
("temperature [K]"). A file with bodies (/bodies/<name>: the meshes) gets, at each time, a
spatial collection of the particles' grid and one triangle grid per body at its pose: the posed
vertices of the frame for a body that moves, the scene's vertices for one that does not. A
frame without particles (a factory-fed scene before its first insertion) cannot be a grid of
zero points: VTK's XDMF reader (ParaView's) fails on its geometry ("Error in Update() of
Geometry") and drops the block. Such a file describes every frame as a spatial collection
holding a "particles" grid, and an empty frame's "particles" as an empty collection, which
reads as an empty block of the same name (tests/unit/test_export.py). The data stay in the
HDF5 file, referenced by its name relative to the XDMF file: keep the two side
by side. Standard library XML and h5py only.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import SceneError

_TYPES = {"f": "Float", "i": "Int", "u": "UInt"}


def _data_item(parent, h5_name: str, path: str, dataset) -> None:
    """<DataItem> for ``dataset`` (h5py) at ``path`` inside ``h5_name``."""
    kind = _TYPES.get(dataset.dtype.kind)
    if kind is None:
        raise SceneError(h5_name, path, f"dtype {dataset.dtype} has no XDMF number type")
    item = ET.SubElement(parent, "DataItem", Dimensions=" ".join(str(n) for n in dataset.shape),
                         NumberType=kind, Precision=str(dataset.dtype.itemsize), Format="HDF")
    item.text = f"{h5_name}:{path}"


def _body_grid(parent, h5_name: str, f, name: str, key: str) -> None:
    """A triangle grid for body ``name`` in frame ``key``: its posed vertices when the frame
    has them (a body that moves), else the scene's."""
    posed = f"frames/{key}/bodies/{name}/vertices"
    vertices = posed if posed in f else f"bodies/{name}/vertices"
    faces = f[f"bodies/{name}/faces"]
    grid = ET.SubElement(parent, "Grid", Name=name, GridType="Uniform")
    topology = ET.SubElement(grid, "Topology", TopologyType="Triangle",
                             NumberOfElements=str(faces.shape[0]))
    _data_item(topology, h5_name, f"/bodies/{name}/faces", faces)
    geometry = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
    _data_item(geometry, h5_name, "/" + vertices, f[vertices])


def foreign_xdmf_problem(xdmf_path) -> str | None:
    """Why the existing file ``xdmf_path`` must not be replaced by our XDMF (a reason), or None:
    absent, empty, or an XDMF description of a results file's frames as this module writes
    them (an XML Xdmf document whose data items point into /frames/ of an HDF5 file)."""
    p = Path(xdmf_path)
    if not p.is_file():
        return None
    try:
        head = p.read_bytes()[:4096]
    except OSError as err:
        return f"exists and cannot be read ({err.strerror or err}); refusing to overwrite it"
    if not head:
        return None
    if head.lstrip().startswith(b"<?xml") and b"<Xdmf" in head and b":/frames/" in head:
        return None
    return ("exists and is not an XDMF description taichi_dem wrote; refusing to overwrite it "
            "(move it away, or write the XDMF elsewhere: taichi-dem export RESULTS.h5 --xdmf "
            "--out FILE.xdmf)")


def write_xdmf(h5_path, xdmf_path=None) -> tuple[Path, int]:
    """Write the XDMF description of ``h5_path``'s frames (default: beside it, same stem,
    ``.xdmf``); returns (its path, the frames described)."""
    import h5py
    h5_path = Path(h5_path)
    xdmf_path = Path(xdmf_path) if xdmf_path else h5_path.with_suffix(".xdmf")
    # the data reference is relative to the XDMF file when they share a folder
    same_folder = xdmf_path.resolve().parent == h5_path.resolve().parent
    h5_name = h5_path.name if same_folder else str(h5_path.resolve())
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    series = ET.SubElement(domain, "Grid", Name="particles", GridType="Collection",
                           CollectionType="Temporal")
    with h5py.File(h5_path, "r") as f:
        if "frames" not in f or not len(f["frames"]):
            raise SceneError(str(h5_path), "frames", "the results file holds no particle frames "
                                                     "(a run writes them when it has an HDF5 results file)")
        keys = sorted(f["frames"], key=int)
        meshes = f["bodies"] if "bodies" in f else None
        # every frame as a collection holding "particles" when bodies come along, or when some
        # frame has no particle (its "particles" an empty collection: module docstring)
        collections = meshes is not None or any(
            "position" in f["frames"][k] and f["frames"][k]["position"].shape[0] == 0
            for k in keys)
        for key in keys:
            frame = f["frames"][key]
            if "position" not in frame:
                raise SceneError(str(h5_path), f"frames/{key}/position", "missing: a frame "
                                                                         "needs the positions")
            count = frame["position"].shape[0]
            time = repr(float(frame.attrs.get("time", float(key))))
            if not collections:
                grid = ET.SubElement(series, "Grid", Name=f"frame {key}", GridType="Uniform")
                ET.SubElement(grid, "Time", Value=time)
            else:
                at = ET.SubElement(series, "Grid", Name=f"frame {key}", GridType="Collection",
                                   CollectionType="Spatial")
                ET.SubElement(at, "Time", Value=time)
                for name in sorted(meshes) if meshes is not None else ():
                    _body_grid(at, h5_name, f, name, key)
                if count == 0:
                    ET.SubElement(at, "Grid", Name="particles", GridType="Collection",
                                  CollectionType="Spatial")
                    continue
                grid = ET.SubElement(at, "Grid", Name="particles", GridType="Uniform")
            ET.SubElement(grid, "Topology", TopologyType="Polyvertex",
                          NumberOfElements=str(count), NodesPerElement="1")
            geometry = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            _data_item(geometry, h5_name, f"/frames/{key}/position", frame["position"])
            for name in sorted(frame):
                data = frame[name]
                if name == "position" or not hasattr(data, "shape") or not data.shape \
                        or data.shape[0] != count:
                    continue
                if data.ndim == 1:
                    kind = "Scalar"
                elif data.ndim == 2 and data.shape[1] == 3:
                    kind = "Vector"
                else:
                    continue
                unit = data.attrs.get("units")
                label = f"{name} [{unit}]" if unit not in (None, "1") else name
                attribute = ET.SubElement(grid, "Attribute", Name=label, AttributeType=kind,
                                          Center="Node")
                _data_item(attribute, h5_name, f"/frames/{key}/{name}", data)
    ET.indent(root)
    problem = foreign_xdmf_problem(xdmf_path)
    if problem:
        raise SceneError(str(xdmf_path), "", problem)
    xdmf_path.write_text('<?xml version="1.0" ?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n'
                         + ET.tostring(root, encoding="unicode") + "\n")
    return xdmf_path, len(keys)


__all__ = ["write_xdmf"]
