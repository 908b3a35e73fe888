"""The keys of a region (a box or a cylinder), declared once for every section that takes
one: fills, factories, outlets, sensors' boxes, radiation. Read by sections/particles.py."""
from __future__ import annotations

from ..keys import REQUIRED, Key, Section, register

_P = dict(minimum=0.0, exclusive_minimum=True)      # > 0

BOX = register(Section("region.box", "An axis-aligned box", (
    Key("min", "vector", "the lower corner", unit="length", default=REQUIRED),
    Key("max", "vector", "the upper corner", unit="length", default=REQUIRED),
), owner=__name__))
CYLINDER = register(Section("region.cylinder", "A solid cylinder", (
    Key("axis_point", "vector", "the centre of one end", unit="length", default=REQUIRED),
    Key("axis_direction", "direction", "the axis, from that end", default=REQUIRED),
    Key("radius", "quantity", "the radius", unit="length", default=REQUIRED, **_P),
    Key("length", "quantity", "the length along the axis", unit="length", default=REQUIRED, **_P),
), owner=__name__))
REGION = register(Section("region", "A region: exactly one of box or cylinder", (
    Key("box", "table", "{ min, max }", default=None),
    Key("cylinder", "table", "{ axis_point, axis_direction, radius, length }", default=None),
), owner=__name__, nested={"box": BOX, "cylinder": CYLINDER}))
REGION_KINDS = REGION.names
BOX_KEYS = BOX.names
CYLINDER_KEYS = CYLINDER.names
