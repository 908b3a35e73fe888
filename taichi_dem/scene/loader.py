"""Scene TOML -> :class:`~taichi_dem.scene.Scene`, with strict validation.

Every problem is a :class:`~taichi_dem.scene.SceneError` naming the file, the dotted TOML key
(``materials.ash.poisson_ratio``, ``particles[2].radius``) and what was wrong and what is allowed.
Unknown keys are errors (with the closest valid key suggested), so a typo never silently falls
back to a default.

Each section's keys are declared (scene/keys.py) where the section is read: the scene's own
sections in ``scene/sections/`` (simulation, domain and output; materials and interactions;
walls and bodies; particle fills and regions; factories, outlets and sensors), the effects'
sections with their effects (``effects/mobility/settings.py``, ``effects/drag/settings.py``,
``thermal/settings.py``). This module reads the document in order and hands each section to
its reader; ``scene/schema.py`` turns the same declarations into a JSON Schema.
"""
from __future__ import annotations

import re
import tomllib
from pathlib import Path


from . import catalog as _catalog  # noqa: F401 (registers the effects' sections)
from ..errors import SceneError
from .keys import added_in, effect_sections, suggest as _suggest, table_sections
from .model import Scene
from .sections.common import Reader, decode_utf8 as _decode_utf8, refuse_control_characters
from .sections.materials import MaterialSections
from .sections.consistency import ConsistencySections
from .sections.particles import ParticleSections, region_bounds  # noqa: F401 (re-exported)
from .sections.process import ProcessSections
from .sections.simulation import SimulationSections
from .sections.surfaces import SurfaceSections

# the sections this module reads itself; every effect section that is a table of its own
# (scene/catalog.py) is accepted too
BUILT_IN_SECTIONS = ("simulation", "domain", "materials", "interactions", "particles", "walls",
                     "bodies", "factories", "outlets", "sensors", "output")
SECTIONS = BUILT_IN_SECTIONS + tuple(p for p in table_sections() if p not in BUILT_IN_SECTIONS)
PLANNED_SECTIONS: tuple[str, ...] = ()


def load_scene(path) -> Scene:
    """Read and validate a scene file. A missing file or a TOML syntax error is a SceneError."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise SceneError(str(p), "", "scene file not found") from None
    except IsADirectoryError:
        raise SceneError(str(p), "", "is a directory, expected a scene TOML file") from None
    except OSError as e:
        raise SceneError(str(p), "", f"cannot read the scene file: {e.strerror or e}") from None
    text = _decode_utf8(data, str(p), "")
    return parse_scene(text, source=str(p), base_dir=p.parent)


def read_toml(text: str, source: str = "<string>") -> dict:
    """The TOML document ``text`` as a dict; a syntax error or a nesting too deep for the
    reader is a SceneError naming ``source`` (and the line) - every reader of a scene's text
    goes through here, so no TOML error reaches the user as a traceback."""
    try:
        return tomllib.loads(text)
    except RecursionError:
        # tomllib reads nested arrays and inline tables recursively: a few hundred levels
        # exhaust Python's stack (no scene key nests more than five)
        raise SceneError(source, "", f"the TOML nests arrays or inline tables too deeply to "
                                     f"be read (more than a few hundred levels, from line "
                                     f"{_deepest_line(text)}); no scene key nests more than a "
                                     f"few levels") from None
    except tomllib.TOMLDecodeError as e:
        msg = str(e)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        if m:
            what = msg[:m.start()].strip()
            reason = f"TOML syntax error at line {m.group(1)}, column {m.group(2)}: {what}"
        elif "end of document" in msg:
            what = msg.replace("(at end of document)", "").strip()
            n = max(1, len(text.splitlines()))
            reason = f"TOML syntax error at line {n} (end of document): {what}"
        else:
            reason = f"TOML syntax error: {msg}"
        raise SceneError(source, "", reason) from None


def parse_scene(text: str, source: str = "<string>", base_dir=None) -> Scene:
    """Validate TOML ``text``; relative particle files resolve against ``base_dir`` (default:
    the directory of ``source`` when it is a path, else the current directory)."""
    doc = read_toml(text, source)
    refuse_control_characters(doc, source)
    if base_dir is None:
        base_dir = Path(source).parent if not source.startswith("<") else Path.cwd()
    return _Parser(source, Path(base_dir)).scene(doc, text)


def _deepest_line(text: str, depth: int = 100) -> int:
    """The line where brackets and braces first open ``depth`` deep (strings and comments
    not told apart: a pointer for the message, not a parse)."""
    level, line = 0, 1
    for m in re.finditer(r"[\[\]{}\n]", text):
        c = m.group()
        if c == "\n":
            line += 1
        else:
            level += 1 if c in "[{" else -1
            if level >= depth:
                return line
    return line


class _Parser(Reader, SimulationSections, MaterialSections, SurfaceSections, ParticleSections,
              ProcessSections, ConsistencySections):
    """One scene document, read section by section (the mixins: scene/sections/)."""

    # -- the scene -----------------------------------------------------------------------------
    def scene(self, doc: dict, text: str) -> Scene:
        for k in doc:
            if k in PLANNED_SECTIONS:
                raise self.err(k, "not supported yet by this version of taichi_dem (planned)")
        for k in doc:
            if k not in SECTIONS:
                raise self.err(k, f"unknown section '{k}'; {_suggest(k, SECTIONS + PLANNED_SECTIONS)}"
                                  f"allowed sections: {', '.join(SECTIONS)}")
        simulation = self.simulation(doc.get("simulation", {}))
        if "domain" not in doc:
            raise self.err("domain", "required section [domain] is missing (min, max, periodic)")
        self.domain = self.parse_domain(doc["domain"])
        self.materials = self.parse_materials(doc.get("materials", {}))
        interactions, _ = self.parse_interactions(self.array_of_tables(doc, "interactions"))
        walls = self.parse_walls(self.array_of_tables(doc, "walls"))
        bodies = self.parse_bodies(self.array_of_tables(doc, "bodies"), walls)
        fills = tuple(self.parse_fill(f, f"particles[{i}]")
                      for i, f in enumerate(self.array_of_tables(doc, "particles")))
        factories = tuple(self.parse_factory(f, f"factories[{i}]")
                          for i, f in enumerate(self.array_of_tables(doc, "factories")))
        self.unique_names(factories, "factories")
        outlets = tuple(self.parse_outlet(o, f"outlets[{i}]")
                        for i, o in enumerate(self.array_of_tables(doc, "outlets")))
        self.unique_names(outlets, "outlets")
        sensors = tuple(self.parse_sensor(x, f"sensors[{i}]", factories, outlets, bodies)
                        for i, x in enumerate(self.array_of_tables(doc, "sensors")))
        self.unique_names(sensors, "sensors")
        output = self.parse_output(doc.get("output", {}))
        self.check_particle_total(simulation, fills, factories)
        sources = tuple(fills) + factories
        self.check_coverage(interactions, sources, walls, bodies)
        self.simulation, self.sources, self.walls, self.bodies = simulation, sources, walls, bodies
        self.doc = doc
        self.check_consistency(doc, simulation, output, sources, walls, bodies)
        # every effect's section, read by its own settings module (scene/keys.py), each after
        # the sections whose settings it reads (Section.after)
        self.settings = {}
        sections = effect_sections()
        for path in _reading_order(sections):
            section = sections[path]
            if path in doc and section.reader is not None:
                read = section.reader(doc[path], self)
                if read is not None:            # (None: the section says it is off)
                    self.settings[path] = read
            elif section.derive is not None:
                implied = section.derive(self)      # (from other sections: [thermal.gas])
                if implied is not None:
                    self.settings[path] = implied
        for path, section in sections.items():
            if section.check_added is not None:
                section.check_added(self)
            if path not in self.settings:
                self.refuse_added_keys(doc, path, section)
        return Scene(source=self.source, text=text, simulation=simulation, domain=self.domain,
                     materials=self.materials, interactions=interactions, fills=fills,
                     walls=walls, bodies=bodies, output=output,
                     factories=factories, outlets=outlets, sensors=sensors,
                     settings=self.settings)

    def refuse_added_keys(self, doc: dict, path: str, section) -> None:
        """A key the effect of ``section`` (at ``path``, not enabled by the scene) adds to
        another section, given there: refused where the key says so (``Key.when_off``)."""
        for host, key in added_in(doc, section):
            if key.when_off == "refused":
                raise self.err(f"{host}.{key.name}", key.off_reason or
                               f"acts only with [{path}], which the scene does not have: add "
                               f"the section or drop the key")


def _reading_order(sections: dict) -> list:
    """The effect sections' paths, each after those it reads (``Section.after``), else in
    their order of registration."""
    out: list = []

    def visit(path, seen=()):
        if path in out or path not in sections:
            return
        assert path not in seen, f"[{path}]: its sections read each other"
        for first in sections[path].after:
            visit(first, seen + (path,))
        out.append(path)
    for path in sections:
        visit(path)
    return out
