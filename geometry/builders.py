"""Mesh builders (registered in geometry/registry.py) (``builder = "..."`` in a scene's ``[[bodies]] mesh``).

Every builder takes keyword parameters in SI (lengths in m; angles in degrees where the name
ends in ``_deg``), places its axis along +x from x = 0, centred on y = z = 0, and returns a
:class:`~geometry.mesh.TriMesh`. Common keys, applied after the shape is made, in this order:
``roll_deg`` (turn about the builder's own +x axis); then, for the builders that take one,
``incline_deg`` (tilt +x down about +y); ``axis_direction`` (turn +x onto it, no roll: see
:func:`geometry._shapes.align_x_to`); ``origin`` (translate); ``max_edge`` (subdivide so no
triangle edge is longer). :func:`body_axis` gives the resulting axis, e.g. for a rotate motion.

A value may be a number (SI, or degrees for ``*_deg``) or a quantity string such as
``"15 mm"`` or ``"0.5 rad"``. ``build(name, params, key=...)`` checks everything and raises
:class:`~geometry.mesh.GeometryError` naming the key (``bodies[0].mesh.flight_height``).

Several meshes make one body through :func:`build_mesh` with a list: for the seed study's
optimised cooler, a ``paddle_shaft`` (which carries the whole shaft) plus a ``screw`` with
``include_shaft = false`` over the inlet section, the paddle rows starting after it::

    mesh = [
      { builder = "paddle_shaft", length = 6.0, shaft_radius = 0.08, start = 1.35, rows = 19,
        paddles_per_row = 4, paddle_length = 0.3, paddle_width = 0.15, paddle_pitch_deg = 30 },
      { builder = "screw", length = 1.2, shaft_radius = 0.08, outer_radius = 0.38,
        pitch = 0.3, turns_direction = "left", include_shaft = false },
    ]

Sense conventions (positive rotation = right-hand rule about the body's +x axis):
a plate's stored normal is the face that leads (pushes) under positive rotation; a positive
``paddle_pitch_deg`` conveys towards +x under positive rotation; a right-hand screw flight
turned positively conveys towards -x (like a nut on a bolt), a left-hand one towards +x.
"""

from __future__ import annotations

import math

import numpy as np

from . import _shapes as sh
from .io import read_mesh
from .mesh import ParameterError, TriMesh
from .registry import (BUILDERS, COMMON, KINDS, MAX_COUNT, REQUIRED, Builder, Param,  # noqa: F401
                       _register, body_axis, build, build_mesh, describe_builders, load_mesh,
                       place, subdivided)

_Bad = ParameterError        # the builders' short name for it

# The range one parameter has by itself in its builder's checks below (the others relate
# several parameters: a flight lower than the radius, an orifice smaller than the top), for
# the JSON Schema (scene/schema.py): (builder, parameter) -> (minimum, maximum, exclusive),
# in the parameter's unit (degrees for *_deg); None: unbounded on that side.
# tests/unit/test_schema.py builds each at and within its bounds.
PARAMETER_RANGES = {
    ("drum", "incline_deg"): (-45.0, 45.0, True),
    ("drum", "flight_lip_angle_deg"): (0.0, 180.0, True),
    ("drum", "segments"): (3, None, False),
    ("paddle_shaft", "paddle_pitch_deg"): (-90.0, 90.0, False),
    ("chute", "incline_deg"): (-90.0, 90.0, True),
}


# ------------------------------------------------------------------------------ helpers
def default_segments(multiple_of: int = 4, chord_error: float = 0.01) -> int:
    """Fewest polygon sides, a multiple of ``multiple_of``, with a sagitta (chord error)
    below ``chord_error`` x radius: R (1 - cos(pi/n)) < 0.01 R needs n >= 23."""
    n_min = math.ceil(math.pi / math.acos(1.0 - chord_error))
    m = max(1, multiple_of)
    return m * math.ceil(n_min / m)


# Surfaces of revolution are cut axially into pieces up to this many times the
# circumferential chord: fewer triangles, still compact bounding boxes for the broadphase.
AXIAL_ASPECT = 3.0


def _chord(radius: float, n: int) -> float:
    return 2.0 * radius * math.sin(math.pi / n)


def _frame(theta: float):
    """Unit radial and tangential (increasing angle, from +y towards +z) vectors."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([0.0, c, s]), np.array([0.0, -s, c])


def _closed_shaft(length: float, radius: float, n: int, phase: float = 0.0) -> TriMesh:
    prof = [(0.0, 0.0), (0.0, radius), (length, radius), (length, 0.0)]
    return sh.revolve(prof, n, phase=phase, normals="left", target=AXIAL_ASPECT * _chord(radius, n))


# ------------------------------------------------------------------------------ box
@_register("box", "an axis-aligned box; a container (normals inward) unless normals = "
                  "\"outward\"", {
    "min": ("point", "one corner"),
    "max": ("point", "the opposite corner"),
    "normals": ("choice", "inward: particles inside (a container); outward: a solid block",
                ("inward", "outward")),
    "open_top": ("bool", "leave out the +z face (an open bin)"),
})
def box(*, min, max, normals="inward", open_top=False) -> TriMesh:
    lo, hi = np.asarray(min, dtype=np.float64), np.asarray(max, dtype=np.float64)
    for i, axis in enumerate("xyz"):
        if hi[i] <= lo[i]:
            raise _Bad("max", f"max.{axis} = {hi[i]:g} must exceed min.{axis} = {lo[i]:g}")
    c = np.array([[lo[0] if i & 1 == 0 else hi[0], lo[1] if i & 2 == 0 else hi[1],
                   lo[2] if i & 4 == 0 else hi[2]] for i in range(8)])
    # outward-wound quads: -x, +x, -y, +y, -z, +z
    quads = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
    if open_top:
        quads = quads[:-1]
    f = np.array([t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))])
    mesh = TriMesh(c, f)
    return mesh.flipped() if normals == "inward" else mesh


# ------------------------------------------------------------------------------ drum
@_register("drum", "a rotary drum: cylindrical shell (normals towards the axis), optional "
                   "end walls, lifting flights (straight or L-shaped plates), incline", {
    "radius": ("length", "inner shell radius (polygon vertices lie on it)"),
    "length": ("length", "shell length along the axis"),
    "end_walls": ("bool", "close both ends (normals into the drum)"),
    "end_hole_radius": ("length0", "radius of a central opening in each end wall "
                                   "(inlet/outlet, a shaft); 0 = solid discs"),
    "include_shell": ("bool", "false: flights (and end walls) only, e.g. a second flight "
                              "section on the same drum"),
    "flights": ("count0", "number of lifting flights, evenly spaced"),
    "flight_height": ("length", "radial height of a flight (required when flights > 0)"),
    "flight_shape": ("choice", "cross-section of a flight", ("straight", "L")),
    "flight_lip": ("length", "length of the L foot (lip) at the flight tip (required for "
                             "flight_shape = \"L\")"),
    "flight_lip_angle_deg": ("angle", "angle between the radial plate and the lip; 90 = L"),
    "flight_lip_side": ("choice", "which way the lip points: leading = towards increasing "
                                  "angle (the leading side under positive rotation)",
                        ("leading", "trailing")),
    "flight_thickness": ("length0", "0 = single-layer two-sided plates; > 0 = closed solids"),
    "flight_start": ("length0", "x where the flights begin"),
    "flight_end": ("length", "x where the flights end (default: length)"),
    "flight_phase_deg": ("angle", "angle of the first flight, from +y towards +z"),
    "incline_deg": ("angle", "axis tilted down by this along +x: axis = (cos a, 0, -sin a) "
                             "before axis_direction; give the same axis to the rotate motion"),
    "segments": ("count", "polygon sides of the shell (default: chord error < 1 % of radius, "
                          "a multiple of flights)"),
})
def drum(*, radius, length, end_walls=True, end_hole_radius=0.0, include_shell=True,
         flights=0, flight_height=None, flight_shape="straight", flight_lip=None,
         flight_lip_angle_deg=90.0, flight_lip_side="leading", flight_thickness=0.0,
         flight_start=0.0, flight_end=None, flight_phase_deg=0.0, incline_deg=0.0,
         segments=None) -> TriMesh:
    R, L = radius, length
    if end_hole_radius >= R:
        raise _Bad("end_hole_radius", f"{end_hole_radius:g} m must be smaller than the "
                                      f"radius {R:g} m")
    if not -45.0 < incline_deg < 45.0:
        raise _Bad("incline_deg", f"{incline_deg:g} deg is not a drum incline (|a| < 45 deg)")
    n = segments if segments is not None else default_segments(max(flights, 4))
    if n < 3:
        raise _Bad("segments", f"a polygon needs at least 3 sides, got {n}")
    phase = math.radians(flight_phase_deg)
    target = AXIAL_ASPECT * _chord(R, n)
    parts = []
    h = end_hole_radius
    if include_shell:
        prof = [(0.0, h), (0.0, R), (L, R), (L, h)] if end_walls else [(0.0, R), (L, R)]
        parts.append(sh.revolve(prof, n, phase=phase, normals="right", target=target))
    elif end_walls:
        parts.append(sh.revolve([(0.0, h), (0.0, R)], n, phase=phase, target=target))
        parts.append(sh.revolve([(L, R), (L, h)], n, phase=phase, target=target))
    if flights > 0:
        parts += _drum_flights(R, L, flights, flight_height, flight_shape, flight_lip,
                               flight_lip_angle_deg, flight_lip_side, flight_thickness,
                               flight_start, flight_end, phase, target)
    if not parts:
        raise _Bad("include_shell", "nothing to build: no shell, no end walls, no flights")
    return sh.weld(TriMesh.concatenate(parts))      # incline_deg: applied by place()


def _drum_flights(R, L, count, height, shape, lip, lip_angle_deg, lip_side, thickness,
                  x0, x1, phase, target):
    if height is None:
        raise _Bad("flight_height", f"missing: {count} flights need flight_height")
    if height >= R:
        raise _Bad("flight_height", f"{height:g} m must be smaller than the radius {R:g} m")
    x1 = L if x1 is None else x1
    if x1 > L + 1e-12:
        raise _Bad("flight_end", f"{x1:g} m is beyond the drum length {L:g} m")
    if x1 <= x0:
        raise _Bad("flight_start", f"flight_start {x0:g} m must be before flight_end {x1:g} m")
    # cross-section in (radial, tangential) coordinates
    section = [(R, 0.0), (R - height, 0.0)]
    if shape == "L":
        if lip is None:
            raise _Bad("flight_lip", "missing: L-shaped flights need flight_lip (the foot length)")
        a = math.radians(lip_angle_deg)
        if not 0.0 < a < math.pi:
            raise _Bad("flight_lip_angle_deg", f"{lip_angle_deg:g} deg: must be between 0 and "
                                               "180 (90 = L)")
        sign = 1.0 if lip_side == "leading" else -1.0
        end = (R - height - lip * math.cos(a), sign * lip * math.sin(a))
        r_end = math.hypot(*end)
        if r_end >= R - 0.5 * thickness:
            raise _Bad("flight_lip", f"the lip reaches r = {r_end:.4g} m, through the shell "
                                     f"(radius {R:g} m); shorten it or raise flight_height")
        section.append(end)
    elif lip is not None:
        raise _Bad("flight_lip", "a lip needs flight_shape = \"L\"")
    if thickness > 0 and count > 1 and thickness >= _chord(R - height, count):
        raise _Bad("flight_thickness", f"{thickness:g} m: thicker than the flight spacing")
    sec = sh.subdivide_polyline(np.asarray(section), target)
    nx = sh.pieces(x1 - x0, target)
    sh.afford(2.0 * count * nx * len(sec), "triangles in the flights")
    xs = np.linspace(x0, x1, nx + 1)
    # 2-D normals of the section polyline (for thick flights), mitred at corners
    seg = np.diff(sec, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    seg_n = np.stack([-seg[:, 1], seg[:, 0]], axis=1)
    vn = np.zeros_like(sec)
    vn[:-1] += seg_n
    vn[1:] += seg_n
    vn /= np.linalg.norm(vn, axis=1, keepdims=True)
    cosines = np.ones(len(sec))
    for k in range(1, len(sec) - 1):
        cosines[k] = max(0.2, float(vn[k] @ seg_n[k]))
    vn /= cosines[:, None]
    out = []
    for k in range(count):
        e_r, e_t = _frame(phase + 2.0 * math.pi * k / count)
        p2 = sec[:, :1] * e_r + sec[:, 1:] * e_t                 # (m, 3), x = 0
        grid = xs[:, None, None] * np.array([1.0, 0.0, 0.0]) + p2[None]   # (nx, m, 3)
        if thickness > 0.0:
            off = (vn[:, :1] * e_r + vn[:, 1:] * e_t) * thickness
            out.append(sh.slab(grid, np.broadcast_to(off, grid.shape)))
        else:
            # dP/dx x dP/dsection = x x (-e_r) = -e_t: flip so the normal leads (+e_t)
            out.append(sh.sheet(grid, two_sided=True, flip=True))
    return out


# ------------------------------------------------------------------------------ paddle shaft
@_register("paddle_shaft", "a shaft with rows of flat paddles (pitched plates), as in a "
                           "paddle cooler or mixer", {
    "length": ("length", "shaft length along the axis"),
    "shaft_radius": ("length", "shaft radius"),
    "rows": ("count", "number of paddle rows along the shaft"),
    "paddles_per_row": ("count", "paddles per row, evenly spaced round the shaft"),
    "paddle_length": ("length", "radial length from the shaft surface to the tip (default: "
                                "up to shell_radius - clearance, else 3 x shaft_radius)"),
    "paddle_width": ("length", "width of the plate (default: half the row spacing)"),
    "paddle_thickness": ("length0", "0 = single-layer two-sided plates; > 0 = closed boxes"),
    "paddle_pitch_deg": ("angle", "angle of the paddle face to the axis: 0 = face contains "
                                  "the axis (no conveying), > 0 conveys towards +x under "
                                  "positive rotation"),
    "stagger_deg": ("angle", "phase shift of each row relative to the previous one"),
    "phase_deg": ("angle", "angle of the first paddle of the first row, from +y towards +z"),
    "start": ("length0", "x of the first row's centre (default: the pattern is centred)"),
    "row_spacing": ("length", "axial distance between rows (default: length / rows, or what "
                              "fits after start)"),
    "include_shaft": ("bool", "false: paddles only (to share a shaft with another mesh)"),
    "shell_radius": ("length", "radius of the surrounding shell, to check the tip clearance"),
    "clearance": ("length", "tip clearance for the default paddle_length (default: 5 % of "
                            "shell_radius)"),
    "segments": ("count", "polygon sides of the shaft (default: chord error < 1 %)"),
})
def paddle_shaft(*, length, shaft_radius, rows, paddles_per_row, paddle_length=None,
                 paddle_width=None, paddle_thickness=0.0, paddle_pitch_deg=0.0, stagger_deg=0.0,
                 phase_deg=0.0, start=None, row_spacing=None, include_shaft=True,
                 shell_radius=None, clearance=None, segments=None) -> TriMesh:
    L, rs = length, shaft_radius
    if shell_radius is not None and shell_radius <= rs:
        raise _Bad("shell_radius", f"{shell_radius:g} m must exceed shaft_radius {rs:g} m")
    if clearance is not None and shell_radius is None:
        raise _Bad("clearance", "needs shell_radius")
    if paddle_length is None:
        if shell_radius is not None:
            gap = clearance if clearance is not None else 0.05 * shell_radius
            paddle_length = shell_radius - gap - rs
            if paddle_length <= 0:
                raise _Bad("clearance", f"{gap:g} m leaves no room for paddles between the "
                                        f"shaft ({rs:g} m) and the shell ({shell_radius:g} m)")
        else:
            paddle_length = 3.0 * rs
    # row placement
    if row_spacing is None:
        if start is None:
            row_spacing, start = L / rows, 0.5 * L / rows
        else:
            if start >= L:
                raise _Bad("start", f"{start:g} m is beyond the shaft length {L:g} m")
            row_spacing = (L - start) / (rows - 0.5)
    elif start is None:
        start = 0.5 * (L - (rows - 1) * row_spacing)
    W = 0.5 * row_spacing if paddle_width is None else paddle_width
    t = paddle_thickness
    beta = math.radians(paddle_pitch_deg)
    if not -90.0 <= paddle_pitch_deg <= 90.0:
        raise _Bad("paddle_pitch_deg", f"{paddle_pitch_deg:g}: must be within [-90, 90]")
    half_axial = 0.5 * (W * abs(math.cos(beta)) + t * abs(math.sin(beta)))
    last = start + (rows - 1) * row_spacing
    if start - half_axial < -1e-9 * L:
        raise _Bad("start", f"the first row at x = {start:g} m reaches x = "
                            f"{start - half_axial:.4g} m, off the shaft's start (x = 0)")
    if last + half_axial > L * (1 + 1e-9):
        raise _Bad("rows", f"{rows} rows {row_spacing:.4g} m apart from x = {start:.4g} m "
                           f"reach x = {last + half_axial:.4g} m, beyond the shaft length "
                           f"{L:g} m (fewer rows, a smaller row_spacing or start)")
    tip = rs + paddle_length
    corner = math.hypot(tip, 0.5 * W * abs(math.sin(beta)) + 0.5 * t * abs(math.cos(beta)))
    if shell_radius is not None and corner >= shell_radius:
        raise _Bad("paddle_length", f"the paddle tips reach r = {corner:.4g} m, not inside the "
                                    f"shell (radius {shell_radius:g} m, gap to the shaft "
                                    f"{shell_radius - rs:.4g} m)")
    n = segments if segments is not None else default_segments(max(4, paddles_per_row))
    parts = [_closed_shaft(L, rs, n)] if include_shaft else []
    if rows * paddles_per_row > MAX_COUNT:
        raise _Bad("rows", f"{rows} rows of {paddles_per_row} paddles: more than "
                           f"{MAX_COUNT:,} paddles is absurd for a mesh")
    sh.pieces(paddle_length, W, "pieces along a paddle")     # refuses an absurd ratio
    na = max(1, round(paddle_length / W))
    sh.afford(4.0 * na * rows * paddles_per_row, "triangles in the paddles")
    a = np.linspace(0.0, paddle_length, na + 1)
    b = np.array([-0.5 * W, 0.5 * W])
    ex = np.array([1.0, 0.0, 0.0])
    for i in range(rows):
        xc = start + i * row_spacing
        for j in range(paddles_per_row):
            theta = math.radians(phase_deg + i * stagger_deg) + 2 * math.pi * j / paddles_per_row
            e_r, e_t = _frame(theta)
            w = math.cos(beta) * ex - math.sin(beta) * e_t
            lead = math.cos(beta) * e_t + math.sin(beta) * ex       # = -(e_r x w)
            grid = (xc * ex + (rs + a)[:, None, None] * e_r + b[None, :, None] * w)
            if t > 0.0:
                parts.append(sh.slab(grid, lead * t))
            else:
                # dP/da x dP/db = e_r x w = -lead: flip so the normal is the leading face
                parts.append(sh.sheet(grid, two_sided=True, flip=True))
    if not parts:
        raise _Bad("include_shaft", "nothing to build")
    return TriMesh.concatenate(parts)


# ------------------------------------------------------------------------------ screw
@_register("screw", "a helicoid screw flight (one or more starts) on a shaft; can share a "
                    "shaft with paddles (include_shaft = false on one of them)", {
    "length": ("length", "axial length of the flighted part (or give turns)"),
    "shaft_radius": ("length", "shaft radius = inner radius of the flight"),
    "outer_radius": ("length", "outer radius of the flight"),
    "pitch": ("length", "axial advance per turn"),
    "turns": ("factor", "number of turns (default: length / pitch)"),
    "turns_direction": ("choice", "handedness of the helix; a right-hand flight turned in the "
                                  "positive sense conveys towards -x", ("right", "left")),
    "starts": ("count", "number of intertwined flights (multi-start screw)"),
    "start": ("length0", "x where the flight begins"),
    "phase_deg": ("angle", "angle where the flight begins, from +y towards +z"),
    "flight_thickness": ("length0", "0 = single-layer two-sided sheet; > 0 = closed solid, "
                                    "thickness along the axis"),
    "include_shaft": ("bool", "false: the flight only (to share a shaft with another mesh)"),
    "shaft_length": ("length", "shaft from x = 0 to this (default: start + length)"),
    "shell_radius": ("length", "radius of the surrounding trough/shell, to check clearance"),
    "segments_per_turn": ("count", "angular resolution (default: chord error < 1 % of "
                                   "outer_radius)"),
    "radial_segments": ("count", "radial resolution (default: near-square triangles)"),
}, aliases={"handedness": "turns_direction"})
def screw(*, length=None, shaft_radius, outer_radius, pitch, turns=None,
          turns_direction="right", starts=1, start=0.0, phase_deg=0.0, flight_thickness=0.0,
          include_shaft=True, shaft_length=None, shell_radius=None, segments_per_turn=None,
          radial_segments=None) -> TriMesh:
    rs, ro, p = shaft_radius, outer_radius, pitch
    if ro <= rs:
        raise _Bad("outer_radius", f"{ro:g} m must exceed shaft_radius {rs:g} m")
    if shell_radius is not None and ro >= shell_radius:
        raise _Bad("outer_radius", f"{ro:g} m: the flight does not fit in the shell "
                                   f"(radius {shell_radius:g} m)")
    if length is None and turns is None:
        raise _Bad("length", "missing: give length (of the flighted part) or turns")
    if length is None:
        length = turns * p
    elif turns is None:
        turns = length / p
    elif abs(turns * p - length) > 1e-6 * length:
        raise _Bad("turns", f"{turns:g} turns of pitch {p:g} m make {turns * p:.6g} m, not "
                            f"length = {length:g} m; give one of them")
    if flight_thickness > 0 and flight_thickness >= p / starts:
        raise _Bad("flight_thickness", f"{flight_thickness:g} m: not less than the distance "
                                       f"between flights, {p / starts:.4g} m")
    if shaft_length is None:
        shaft_length = start + length
    elif shaft_length < start + length - 1e-9:
        raise _Bad("shaft_length", f"{shaft_length:g} m is shorter than the flighted part, "
                                   f"which ends at x = {start + length:g} m")
    spt = segments_per_turn if segments_per_turn is not None else default_segments(4)
    n_theta = max(2, sh.pieces(turns * spt, 1.0, "steps along the helix"))
    arc = 2.0 * math.pi * ro / spt
    nr = radial_segments if radial_segments is not None else \
        sh.pieces(ro - rs, math.hypot(arc, p / spt), "steps across the flight")
    sh.afford(2.0 * n_theta * nr * starts, "triangles in the flight")
    s = 1.0 if turns_direction == "right" else -1.0
    u = np.linspace(0.0, 2.0 * math.pi * turns, n_theta + 1)        # helix parameter
    r = np.linspace(rs, ro, nr + 1)
    parts = [_closed_shaft(shaft_length, rs, default_segments(4))] if include_shaft else []
    for k in range(starts):
        phi = math.radians(phase_deg) + s * u + 2.0 * math.pi * k / starts
        x = start + p * u / (2.0 * math.pi)
        grid = np.stack([np.broadcast_to(x[:, None], (len(u), len(r))),
                         r[None, :] * np.cos(phi)[:, None],
                         r[None, :] * np.sin(phi)[:, None]], axis=2)
        if flight_thickness > 0.0:
            parts.append(sh.slab(grid, np.array([flight_thickness, 0.0, 0.0])))
        else:
            # dP/du x dP/dr: the face that pushes under positive rotation (-x for right-hand)
            parts.append(sh.sheet(grid, two_sided=True))
    return TriMesh.concatenate(parts)


def helicoid_area(inner_radius: float, outer_radius: float, pitch: float,
                  turns: float = 1.0) -> float:
    """Analytic area of a helicoid flight, m^2: turns x 2 pi x [F(r)] from inner to outer,
    F(r) = (r sqrt(r^2 + c^2) + c^2 ln(r + sqrt(r^2 + c^2))) / 2, c = pitch / (2 pi)."""
    c = pitch / (2.0 * math.pi)

    def F(r):
        q = math.sqrt(r * r + c * c)
        return 0.5 * (r * q + c * c * math.log(r + q))
    return turns * 2.0 * math.pi * (F(outer_radius) - F(inner_radius))


# ------------------------------------------------------------------------------ hopper
@_register("hopper", "a conical or wedge (plane-flow) hopper, open at the orifice and the "
                     "top, normals inward; the axis runs from the orifice (x = 0) up, so give "
                     "axis_direction = [0, 0, 1] to stand it upright", {
    "kind": ("choice", "shape", ("conical", "wedge")),
    "height": ("length", "axial height of the converging section"),
    "top_radius": ("length", "conical: radius at the top"),
    "orifice_radius": ("length", "conical: radius of the orifice"),
    "top_width": ("length", "wedge: width at the top (across y)"),
    "orifice_width": ("length", "wedge: width of the slot orifice"),
    "depth": ("length", "wedge: depth of the slot (along z, the flat end walls)"),
    "spout_length": ("length0", "straight section below the converging one, x from 0"),
    "bin_height": ("length0", "straight section above the converging one"),
    "segments": ("count", "conical: polygon sides (default: chord error < 1 %)"),
})
def hopper(*, kind="conical", height, top_radius=None, orifice_radius=None, top_width=None,
           orifice_width=None, depth=None, spout_length=0.0, bin_height=0.0,
           segments=None) -> TriMesh:
    needs = {"conical": ("top_radius", "orifice_radius"),
             "wedge": ("top_width", "orifice_width", "depth")}
    given = {"top_radius": top_radius, "orifice_radius": orifice_radius, "top_width": top_width,
             "orifice_width": orifice_width, "depth": depth}
    other = "wedge" if kind == "conical" else "conical"
    for name in needs[other]:
        if given[name] is not None and name not in needs[kind]:
            raise _Bad(name, f"is for kind = \"{other}\"; a {kind} hopper takes "
                             f"{', '.join(needs[kind])}")
    for name in needs[kind]:
        if given[name] is None:
            raise _Bad(name, f"missing: a {kind} hopper needs {', '.join(needs[kind])}")
    top = top_radius if kind == "conical" else 0.5 * top_width
    ori = orifice_radius if kind == "conical" else 0.5 * orifice_width
    if ori >= top:
        name = "orifice_radius" if kind == "conical" else "orifice_width"
        raise _Bad(name, f"the orifice must be smaller than the top "
                         f"({2 * ori if kind == 'wedge' else ori:g} m vs "
                         f"{2 * top if kind == 'wedge' else top:g} m)")
    x1, x2 = spout_length, spout_length + height
    prof = [(x1, ori), (x2, top)]
    if spout_length > 0:
        prof.insert(0, (0.0, ori))
    if bin_height > 0:
        prof.append((x2 + bin_height, top))
    prof = np.asarray(prof)
    if kind == "conical":
        n = segments if segments is not None else default_segments(4)
        return sh.revolve(prof, n, normals="right", target=_chord(top, n))
    # wedge: half-width w(x) across y, depth along z
    target = min(depth, 2 * top) / 2
    pts = sh.subdivide_polyline(prof, target)
    xs, ws = pts[:, 0], pts[:, 1]
    nz = sh.pieces(depth, target)
    ny = sh.pieces(2 * top, target)
    sh.afford(4.0 * len(xs) * (nz + ny), "triangles in the hopper")
    zs = np.linspace(-0.5 * depth, 0.5 * depth, nz + 1)
    parts = []
    for side in (-1.0, 1.0):
        grid = np.stack([np.broadcast_to(xs[:, None], (len(xs), len(zs))),
                         side * np.broadcast_to(ws[:, None], (len(xs), len(zs))),
                         np.broadcast_to(zs[None, :], (len(xs), len(zs)))], axis=2)
        parts.append(sh.sheet_facing(grid, [0.0, -side, 0.0]))
    frac = np.linspace(-1.0, 1.0, ny + 1)
    for side in (-1.0, 1.0):
        grid = np.stack([np.broadcast_to(xs[:, None], (len(xs), len(frac))),
                         ws[:, None] * frac[None, :],
                         np.full((len(xs), len(frac)), side * 0.5 * depth)], axis=2)
        parts.append(sh.sheet_facing(grid, [0.0, 0.0, -side]))
    return sh.weld(TriMesh.concatenate(parts))


# ------------------------------------------------------------------------------ chute
@_register("chute", "an open chute: a floor along +x (normal up) with optional side walls "
                    "(normals inward), inclined downwards along +x", {
    "length": ("length", "length of the floor along the flow direction"),
    "width": ("length", "width of the floor (across y)"),
    "incline_deg": ("angle", "the floor descends by this angle along +x"),
    "side_walls": ("bool", "walls along both edges"),
    "wall_height": ("length", "height of the side walls (default: half the width)"),
    "back_wall": ("bool", "a wall across the upstream end (x = 0)"),
})
def chute(*, length, width, incline_deg=0.0, side_walls=True, wall_height=None,
          back_wall=False) -> TriMesh:
    if not -90.0 < incline_deg < 90.0:
        raise _Bad("incline_deg", f"{incline_deg:g}: must be between -90 and 90 deg")
    h = 0.5 * width if wall_height is None else wall_height
    if not (side_walls or back_wall) and wall_height is not None:
        raise _Bad("wall_height", "there are no walls (side_walls = false)")
    target = width / 2
    nx, ny, nz = sh.pieces(length, target), sh.pieces(width, target), sh.pieces(h, target)
    sh.afford(2.0 * (nx * ny + 2 * nx * nz + ny * nz), "triangles in the chute")
    xs = np.linspace(0.0, length, nx + 1)
    ys = np.linspace(-0.5 * width, 0.5 * width, ny + 1)
    zs = np.linspace(0.0, h, nz + 1)

    def grid(a, b, f):
        A, B = np.meshgrid(a, b, indexing="ij")
        return np.stack(f(A, B), axis=2)
    parts = [sh.sheet_facing(grid(xs, ys, lambda x, y: (x, y, 0 * x)), [0, 0, 1])]
    if side_walls:
        for side in (-1.0, 1.0):
            g = grid(xs, zs, lambda x, z: (x, np.full_like(x, side * 0.5 * width), z))
            parts.append(sh.sheet_facing(g, [0, -side, 0]))
    if back_wall:
        parts.append(sh.sheet_facing(grid(ys, zs, lambda y, z: (0 * y, y, z)), [1, 0, 0]))
    return sh.weld(TriMesh.concatenate(parts))      # incline_deg: applied by place()


# ------------------------------------------------------------------------------ file
@_register("file", "import an STL/OBJ/PLY (anything trimesh reads); scale and units "
                   "multiply; the winding is kept (normals: STL convention, out of the solid)", {
    "file": ("path", "path, relative to the scene file's folder"),
    "scale": ("factor", "multiplies the coordinates (after units)"),
    "units": ("choice", "unit of the file's coordinates", ("m", "cm", "mm", "in", "ft", "um")),
    "repair": ("bool", "merge duplicate vertices and drop degenerate/duplicate triangles "
                       "instead of failing"),
    "flip_normals": ("bool", "reverse every triangle (e.g. a container exported as a solid)"),
    "two_sided": ("bool", "mark the faces as two-sided plates (default: true for an open "
                          "surface, false for a watertight solid)"),
})
def file(*, file, scale=1.0, units="m", repair=False, flip_normals=False, two_sided=None,
         base_dir=None) -> TriMesh:
    return read_mesh(file, scale=scale, units=units, repair=repair, flip_normals=flip_normals,
                     two_sided=two_sided, base_dir=base_dir)
