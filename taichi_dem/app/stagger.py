"""A slice of paddle rows with any stagger (issue 44 item 5): ``taichi-dem map --stagger DEG``.

A one-row periodic slice repeats its row with no turn between rows (stagger 0). A machine whose
row k is turned k times the stagger repeats only after the rows that bring the pattern back onto
itself: with p paddles per row (a turn of 360/p maps a row onto itself) that is the smallest n
with n * stagger a whole multiple of 360/p (45 deg and 4 paddles: 2 rows; 30 deg: 3; 22.5 deg:
4; 90 deg: 1, the one-row slice again). The slice that holds that repeating unit is the one-row
slice made n times as long: its period, its shell, its shaft with n rows turned by the stagger,
its fill's region; the hold-up per metre (``--holdup``) sets the count as before.
"""
from __future__ import annotations

import copy
import math

from ..errors import SceneError
from ..scene.units import parse_quantity

MOST_ROWS = 8       # a stagger that repeats only after more rows costs more than it tells


def rows_to_repeat(stagger_deg: float, paddles_per_row: int) -> int:
    """The smallest number of rows after which rows turned by ``stagger_deg`` each (deg)
    repeat, with ``paddles_per_row`` paddles spaced evenly round each row; 0 when none up to
    MOST_ROWS does."""
    symmetry = 360.0 / paddles_per_row
    for n in range(1, MOST_ROWS + 1):
        turns = n * stagger_deg / symmetry
        if abs(turns - round(turns)) < 1e-6:
            return n
    return 0


def _length(value, source: str, key: str) -> float:
    return parse_quantity(value, "length", file=source, key=key)


def _meshes(body: dict) -> list:
    mesh = body.get("mesh")
    return mesh if isinstance(mesh, list) else [mesh] if isinstance(mesh, dict) else []


def staggered_doc(doc: dict, stagger_deg: float, source: str, axis: int,
                  period: float) -> tuple[dict, int]:
    """The scene ``doc`` (a one-row periodic slice along ``axis``, ``period`` m long) made the
    repeating unit of rows turned ``stagger_deg`` each: (the new doc, its number of rows).
    SceneError (file: key: reason) for a slice it cannot be made from."""
    if not math.isfinite(stagger_deg):
        raise SceneError("--stagger", "", f"must be a finite angle in deg, got {stagger_deg}")
    doc = copy.deepcopy(doc)
    bodies = doc.get("bodies", [])
    shafts = [(i, j, m) for i, b in enumerate(bodies) for j, m in enumerate(_meshes(b))
              if m.get("builder") == "paddle_shaft"]
    if len(shafts) != 1:
        raise SceneError(source, "bodies", f"--stagger needs one paddle_shaft mesh (the slice's "
                         f"paddle row), the scene has {len(shafts)}")
    i, j, shaft = shafts[0]
    key = f"bodies[{i}].mesh" + (f"[{j}]" if isinstance(bodies[i]["mesh"], list) else "")
    if shaft.get("rows", 1) != 1 or shaft.get("stagger_deg", 0.0) not in (0, 0.0):
        raise SceneError(source, f"{key}.rows", "--stagger turns the rows of a one-row slice: "
                         "give the slice one row (rows = 1) and no stagger_deg")
    for k in ("start", "row_spacing"):
        if k in shaft:
            raise SceneError(source, f"{key}.{k}", f"--stagger places the rows one period "
                             f"apart itself: drop {k}")
    paddles = shaft.get("paddles_per_row")
    if not isinstance(paddles, int) or paddles < 1:
        raise SceneError(source, f"{key}.paddles_per_row", "--stagger needs the paddles per row")
    n = rows_to_repeat(stagger_deg, paddles)
    if n == 0:
        raise SceneError("--stagger", "", f"{stagger_deg:g} deg with {paddles} paddles per row "
                         f"repeats after more than {MOST_ROWS} rows: choose a stagger that "
                         f"divides into {360.0 / paddles:g} deg in at most {MOST_ROWS} steps "
                         "(45, 30, 22.5, ...)")
    if n == 1:
        return doc, 1
    # every body spans the period (slice_geometry checks it): each builder's length scales
    for bi, b in enumerate(bodies):
        for mj, m in enumerate(_meshes(b)):
            where = f"bodies[{bi}].mesh"
            if "builder" not in m:
                raise SceneError(source, where, "--stagger lengthens the bodies: a mesh from a "
                                 "file cannot be (make it with a builder)")
            if "length" in m:
                m["length"] = _length(m["length"], source, f"{where}.length") * n
    shaft["rows"] = n
    shaft["stagger_deg"] = float(stagger_deg)
    dom = doc["domain"]
    lo, hi = list(dom["min"]), list(dom["max"])
    hi[axis] = lo[axis] + n * period
    dom["max"] = hi
    for fi, fill in enumerate(doc.get("particles", [])):
        region = fill.get("region", {})
        if "cylinder" in region and "length" in region["cylinder"]:
            region["cylinder"]["length"] = _length(region["cylinder"]["length"], source,
                                                   f"particles[{fi}].region.cylinder.length") * n
        elif "box" in region:
            bmin, bmax = list(region["box"]["min"]), list(region["box"]["max"])
            where = f"particles[{fi}].region.box"
            a = _length(bmin[axis], source, f"{where}.min")
            bmax[axis] = a + (_length(bmax[axis], source, f"{where}.max") - a) * n
            region["box"]["max"] = bmax
    return doc, n
