"""[[walls]] (analytic planes) and [[bodies]] (triangle meshes with a prescribed motion):
their keys and checks."""
from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import SceneError
from ..keys import REQUIRED, Key, Section, added_values, host_section, register
from ..keys import type_name as _type_name
from ..model import Body, Motion, PlaneWall, SpeedSchedule
from .simulation import AXES

# a body's mesh may reach this fraction of the domain's size beyond each face of the domain
BODY_DOMAIN_MARGIN = 0.1

PLANE = register(Section("plane", "An infinite plane", (
    Key("point", "vector", "a point on the plane", unit="length", default=REQUIRED),
    Key("normal", "direction", "the normal, pointing to the particles' side", default=REQUIRED),
), owner=__name__))
WALL = register(Section("walls[]", "An analytic plane wall, [[walls]]", (
    Key("name", "string", "its name (for its loads, and for the sensors and effects that "
        "refer to it)", default=REQUIRED),
    Key("plane", "table", "{ point, normal }", default=REQUIRED),
    Key("material", "string", "a material name", default=REQUIRED),
), owner=__name__, nested={"plane": PLANE}))
ROTATE = register(Section("bodies[].motion.rotate", "Rotation about a fixed axis", (
    Key("axis_point", "vector", "a point on the axis", unit="length", default=(0.0, 0.0, 0.0)),
    Key("axis_direction", "direction", "the axis (right-hand rule)", default=(1.0, 0.0, 0.0)),
    Key("speed", "any", "an angular speed, or a schedule [[t, speed], ...] (linear between "
        "points)", unit="angular_speed", default=REQUIRED,
        schema={"anyOf": [{"type": ["number", "string"]}, {"type": "array"}]}),
), owner=__name__))
TRANSLATE = register(Section("bodies[].motion.translate", "Translation at a constant velocity", (
    Key("velocity", "vector", "the velocity", unit="speed", default=REQUIRED),
), owner=__name__))
MOTION = register(Section("bodies[].motion", "A prescribed rigid motion (at rest when absent)", (
    Key("rotate", "table", "{ axis_point, axis_direction, speed }", default=None),
    Key("translate", "table", "{ velocity }", default=None),
), owner=__name__, nested={"rotate": ROTATE, "translate": TRANSLATE}))
BODY = register(Section("bodies[]", "A rigid triangle-mesh body, [[bodies]]: a builder's shape "
                        "(drum shell, paddles, screw, ...) or an STL/OBJ file", (
    Key("name", "string", "its name (for its loads, and for the sensors and effects that "
        "refer to it)", default=REQUIRED),
    Key("material", "string", "a material name", default=REQUIRED),
    Key("mesh", "any", "{ builder = NAME, ...parameters } or { file = PATH, scale, ... }, or an "
        "array of those (geometry/builders.py lists the builders and their parameters)",
        default=REQUIRED, schema={"anyOf": [{"type": "object"}, {"type": "array"}]}),
    Key("motion", "table", "{ rotate = {...} } or { translate = {...} }", default=None),
), owner=__name__, nested={"motion": MOTION}))


class SurfaceSections:
    """Read by the loader's parser (scene/loader.py), which mixes this in with the reading
    helpers of common.Reader."""

    def parse_plane(self, value: Any, key: str):
        t = self.table(value, key, "a table { point = [x, y, z], normal = [nx, ny, nz] }")
        self.check_keys(t, key, PLANE)
        return self.vec3(t["point"], "length", f"{key}.point"), self.direction(t["normal"],
                                                                                f"{key}.normal")

    def parse_walls(self, items: list[dict]) -> tuple[PlaneWall, ...]:
        out: list[PlaneWall] = []
        names: dict[str, str] = {}
        for i, t in enumerate(items):
            key = f"walls[{i}]"
            self.check_keys(t, key, host_section(WALL))
            name = self.group_name(t["name"], f"{key}.name")
            if name in names:
                raise self.err(f"{key}.name", f"duplicate wall name '{name}' (also {names[name]})")
            names[name] = key
            point, normal = self.parse_plane(t["plane"], f"{key}.plane")
            material = self.material_name(t["material"], f"{key}.material")
            out.append(PlaneWall(name=name, point=point, normal=normal, material=material,
                                 effect_values=added_values(WALL.path, t, self.source, key)))
        return tuple(out)

    # -- [[bodies]] ------------------------------------------------------------------------------
    def parse_bodies(self, items: list[dict], walls) -> tuple[Body, ...]:
        out: list[Body] = []
        names: dict[str, str] = {w.name: f"walls[{i}]" for i, w in enumerate(walls)}
        for i, t in enumerate(items):
            key = f"bodies[{i}]"
            self.check_keys(t, key, host_section(BODY))
            name = self.group_name(t["name"], f"{key}.name")
            if name in names:
                raise self.err(f"{key}.name", f"duplicate name '{name}' (also {names[name]}); "
                                              "bodies and walls need distinct names")
            names[name] = key
            material = self.material_name(t["material"], f"{key}.material")
            mesh = self.parse_mesh(t["mesh"], f"{key}.mesh")
            motion = Motion()
            if "motion" in t:
                motion = self.parse_motion(t["motion"], f"{key}.motion", t["mesh"], f"{key}.mesh")
            vertices = np.array(mesh.vertices, dtype=np.float64).reshape(-1, 3)
            faces = np.array(mesh.faces, dtype=np.int64).reshape(-1, 3)
            self.check_inside_domain(vertices, f"{key}.mesh")
            out.append(Body(key=key, name=name, material=material, vertices=vertices,
                            faces=faces, motion=motion,
                            effect_values=added_values(BODY.path, t, self.source, key)))
        return tuple(out)

    def parse_mesh(self, spec: Any, key: str):
        """Build (and validate) a body's ``mesh`` through :mod:`geometry`."""
        from taichi_dem import geometry
        try:
            mesh = geometry.build_mesh(spec, key=key, base_dir=self.base_dir)
            return mesh.validate(key)
        except geometry.GeometryError as e:
            raise self.err(e.key or key, e.reason) from None

    def check_inside_domain(self, vertices: np.ndarray, key: str) -> None:
        dlo, dhi = np.array(self.domain.min, float), np.array(self.domain.max, float)
        margin = BODY_DOMAIN_MARGIN * (dhi - dlo)
        elo, ehi = dlo - margin, dhi + margin
        vlo, vhi = vertices.min(axis=0), vertices.max(axis=0)
        for i, ax in enumerate(AXES):
            if ax in self.domain.periodic:
                continue
            if vlo[i] < elo[i] or vhi[i] > ehi[i]:
                raise self.err(key, f"the body's mesh lies outside the domain: on {ax} it spans "
                                    f"{vlo[i]:g} to {vhi[i]:g} m, the domain {dlo[i]:g} to "
                                    f"{dhi[i]:g} m (a mesh may reach "
                                    f"{100 * BODY_DOMAIN_MARGIN:g} % of the domain's size beyond "
                                    f"it: {elo[i]:g} to {ehi[i]:g} m); enlarge [domain] or move "
                                    "the mesh (origin)")

    def parse_motion(self, value: Any, key: str, mesh_spec: Any, mesh_key: str) -> Motion:
        t = self.table(value, key, "a table { rotate = { axis_point, axis_direction, speed } "
                                   "} and/or { translate = { velocity } }")
        self.check_keys(t, key, MOTION)
        kw: dict[str, Any] = {}
        if "translate" in t:
            k = f"{key}.translate"
            tr = self.table(t["translate"], k, "a table { velocity = [vx, vy, vz] }")
            self.check_keys(tr, k, TRANSLATE)
            kw["velocity"] = self.vec3(tr["velocity"], "speed", f"{k}.velocity")
        if "rotate" in t:
            k = f"{key}.rotate"
            rot = self.table(t["rotate"], k, "a table { axis_point, axis_direction, speed }")
            self.check_keys(rot, k, ROTATE)
            kw["speed"] = self.parse_speed(rot["speed"], f"{k}.speed")
            point = direction = None
            if "axis_point" in rot:
                point = self.vec3(rot["axis_point"], "length", f"{k}.axis_point")
            if "axis_direction" in rot:
                direction = self.direction(rot["axis_direction"], f"{k}.axis_direction")
            if point is None or direction is None:
                missing = "axis_point" if point is None else "axis_direction"
                axis = self.builder_axis(mesh_spec, mesh_key)
                if axis is None:
                    raise self.err(f"{k}.{missing}",
                                   "required key is missing: the mesh is not made by a builder, "
                                   "so it has no axis of its own to rotate about")
                if point is None:
                    point = tuple(float(c) for c in axis[0])
                if direction is None:
                    d = np.asarray(axis[1], float)
                    direction = tuple(float(c) for c in d / np.linalg.norm(d))
            kw["axis_point"] = point
            kw["axis_direction"] = direction
        return Motion(**kw)

    def builder_axis(self, spec: Any, key: str):
        """The placed +x axis ``(point, direction)`` of the first mesh of ``spec`` when a
        builder makes it, else None (an imported file has no axis of its own)."""
        from taichi_dem import geometry
        body_axis = getattr(geometry, "body_axis", None)
        first = spec[0] if isinstance(spec, list) and spec else spec
        if body_axis is None or not isinstance(first, dict) or "builder" not in first \
                or first.get("builder") == "file":
            return None
        try:
            return body_axis(first, key=f"{key}[0]" if isinstance(spec, list) else key)
        except geometry.GeometryError as e:
            raise self.err(e.key or key, e.reason) from None

    def parse_speed(self, value: Any, key: str) -> SpeedSchedule:
        """An angular speed ("10 rpm", rad/s) or a schedule [[t0 = 0, w0], [t1, w1], ...]."""
        if not isinstance(value, list):
            try:
                w = self.q(value, "angular_speed", key)
            except SceneError as e:
                raise self.err(key, f"{e.reason}; speed is an angular speed (\"10 rpm\", rad/s) "
                                    "or a schedule [[0.0, \"10 rpm\"], [30.0, \"20 rpm\"]]") from None
            return SpeedSchedule(points=((0.0, w),))
        if not value:
            raise self.err(key, "an empty schedule; give [[0.0, \"10 rpm\"], ...] (start time, "
                                "angular speed)")
        points: list[tuple[float, float]] = []
        for j, item in enumerate(value):
            k = f"{key}[{j}]"
            if not isinstance(item, list) or len(item) != 2:
                raise self.err(k, f"expected [start time, angular speed], e.g. [30.0, \"20 rpm\"], "
                                  f"got {_type_name(item)}"
                                  + (f" of length {len(item)}" if isinstance(item, list) else ""))
            start = self.nonnegative(item[0], "time", f"{k}[0]")
            w = self.q(item[1], "angular_speed", f"{k}[1]")
            if j == 0 and start != 0.0:
                raise self.err(f"{k}[0]", f"the schedule must start at time 0, got {start:g} s "
                                          "(the speed before the first entry would be undefined)")
            if points and not start > points[-1][0]:
                raise self.err(f"{k}[0]", f"start times must increase: {start:g} s follows "
                                          f"{points[-1][0]:g} s")
            points.append((start, w))
        return SpeedSchedule(points=tuple(points))
