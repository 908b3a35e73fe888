"""The schema is as strict as the loader (issue 43, item 5): every parseable scene of the fuzz
corpus (scene_fuzz.py: the hand-written categories and the ones drawn from the schema) goes
through both the loader (``load_scene``) and ``taichi-dem schema`` (``jsonschema``, Draft
2020-12, with TOML's integers: scene/schema.py ``validator``), and the two must agree.

The only disagreements allowed are the loader's checks that a JSON Schema cannot express,
listed in EXEMPT with the reason each cannot be in a schema; a refusal by the loader is
matched to one by its message. Nothing the schema refuses may be accepted by the loader.

TOML has nan and inf (and dates), JSON has not: ``schema.json_compatible`` turns each into
the object ``{"x-toml-only": "nan"}``, which no key of the schema accepts, as the loader
refuses them everywhere. A TOML syntax error (unparseable) is out of the comparison: there
is no document to validate.
"""
import collections
import re
import sys
import tomllib
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import scene_fuzz as sf  # noqa: E402

from taichi_dem.errors import SceneError  # noqa: E402
from taichi_dem.scene import schema  # noqa: E402
from taichi_dem.scene.loader import load_scene  # noqa: E402

SEED = 4302
CASES = 700                # of the corpus, all categories (about 1 in 4 drawn from the schema)

# (name, why a JSON Schema cannot say it, the loader's reasons it covers)
EXEMPT = [
    ("cross-reference", "a name that must be defined elsewhere in the scene (a pair's or a "
     "fill's material, a sensor's factory, outlet or body, radiation_to's wall) or unique "
     "across items: JSON Schema validates a value against a schema, not against other values",
     r"unknown material|no interaction for the material pair|^duplicate|already the name of|"
     r"no factory named|no outlet named|no body named|unknown body|the name of a wall or body"),
    ("file", "what a named file holds or whether it exists (particle CSV and HDF5 fills, mesh "
     "files): the schema sees the path, not the file",
     r"not found|no such file|cannot read|cannot open|holds no|is a directory|are not finite|"
     r"across after units|not a UTF-8 text file|^line \d+|the file holds|no particle frames"),
    ("geometry", "relations between several numbers of one scene: a box's max above its min, "
     "a region inside the domain, a fill that fits its region, a sheet's face and capacity, a "
     "mesh's size and its builder's parts (an orifice smaller than the top, paddles inside the "
     "shell), a mesh inside the domain, degenerate triangles",
     r"must exceed min|must exceed min\.|max must not be below|must lie inside|does not fit|"
     r"spheres of radius|the domain is .* across|the mesh is .* across|the mesh would need|"
     r"must be smaller than|must exceed|leaves no room|through a .* face at|narrower than|"
     r"lies outside the domain|the body's mesh|degenerate|perpendicular|the face|"
     r"beyond the|off the shaft|reach|make .* not length|not less than the distance|"
     r"shorter than the flighted|is for kind|thicker than|wholly behind|points away"),
    ("quantity string", "a quantity string's value after unit conversion (its range, its SI "
     "magnitude 1e-30 to 1e30, a temperature above 0 K in C or F): the pattern checks the "
     "spelling and the dimension; JSON Schema has no units to convert with",
     None),     # matched by is_quantity_string_value below
    ("order and sum", "relations between the entries of one value: a schedule's start times "
     "from 0 and increasing, a size mix's mass fractions summing to 1, min <= mean <= max, a "
     "frame interval a whole multiple of the interval, the real modulus above the softened one",
     r"must start at time 0|start times must increase|must sum to 1|min <= mean <= max|"
     r"whole multiple of|real \(unsoftened\) modulus|one radius \(its lattice"),
    ("another section", "a key that needs another section, or one that depends on the scene's "
     "particles or gravity: thermal properties with [thermal], drying without it, a [gas] "
     "beside a [thermal.gas], coarse graining with a hot wall, a mobility cell two diameters "
     "wide, \"auto\" without gravity",
     r"required when \[thermal\]|required when radiation|has a temperature and \[thermal\]|"
     r"drying needs|\[thermal\.gas\] already|"
     r"coarse graining|a heat law|acts between particles and walls|largest diameters|"
     r"scales with g d|has nothing to conduct|the mesh is not made by a builder|"
     r"no temperature \(it is adiabatic\)|needs a \[thermal\.gas\]"),
    ("physical sanity", "what the scene's numbers imply together: the time step, the number "
     "of steps, the memory, the particles the schedules insert, a damping time against the "
     "step",
     r"time step|steps|memory|can index|insert about|time_constant|placed"),
]


def _path(doc, key: str):
    """The value at the dotted key ``key`` of ``doc`` (None when there is none)."""
    node = doc
    for part in re.findall(r"\[(\d+)\]|([^.\[\]]+)", key):
        index, name = part
        try:
            node = node[int(index)] if index else node[name]
        except (KeyError, IndexError, TypeError, ValueError):
            return None
    return node


def is_quantity_string_value(error: SceneError, doc) -> bool:
    """The loader refused a string's value after converting its unit: the key holds a
    quantity string (or a vector or a builder's point holds one) and the reason is not
    about its type, spelling or unit (which the pattern checks)."""
    value = _path(doc, error.key)
    strings = [value] if isinstance(value, str) else \
        [v for v in value if isinstance(v, str)] if isinstance(value, list) else []
    if not strings or not all(re.search(r"\d", v) for v in strings):
        return False
    return "not a finite number" in error.reason or not re.search(
        r"expected|unknown|cannot read|control character|is an? ", error.reason)


def exemption(error: SceneError, doc, scene: Path):
    """The EXEMPT entry a refusal by the loader falls under, or None."""
    if Path(error.file).name != scene.name:
        return "file"                 # the error names the CSV, HDF5 or mesh file itself
    for name, _, pattern in EXEMPT:
        if pattern is None:
            if is_quantity_string_value(error, doc):
                return name
        elif re.search(pattern, error.reason):
            return name
    return None


BASES = sf.base_scenes()
CORPUS = sf.Fuzzer(BASES).corpus(CASES, SEED) + sf.Fuzzer(BASES).inconsistent_cases(16, SEED)
VALIDATOR = schema.validator()


def compare(case, folder: Path):
    """(loader's error or None, schema's errors) for ``case``; None when it is not TOML."""
    try:
        doc = tomllib.loads(case.text.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
        return None
    scene = sf.write_case(case, folder)
    try:
        load_scene(scene)
        error = None
    except SceneError as e:
        error = e
    return doc, scene, error, list(VALIDATOR.iter_errors(schema.json_compatible(doc)))


def test_the_schema_and_the_loader_agree(tmp_path):
    """Each parseable case: accepted by both or refused by both, except a loader refusal
    EXEMPT lists (with why a schema cannot say it); a schema refusal the loader accepts is
    never allowed."""
    used = collections.Counter()
    compared = 0
    problems = []
    for n, case in enumerate(CORPUS):
        got = compare(case, tmp_path / f"c{n:04d}")
        if got is None:
            continue
        compared += 1
        doc, scene, error, errors = got
        if error is None and errors:
            first = errors[0]
            problems.append(f"{case.ident}: the loader accepts, the schema refuses at "
                            f"{list(first.absolute_path)}: {first.message[:200]}")
        elif error is not None and not errors:
            why = exemption(error, doc, scene)
            if why is None:
                problems.append(f"{case.ident}: the schema accepts, the loader refuses: "
                                f"{error.key}: {error.reason[:200]}")
            used[why] += 1
    assert compared > 0.8 * len(CORPUS) - 150, compared
    assert not problems, ("\n".join(problems[:30])
                          + f"\n({len(problems)} in all; exempt: {dict(used)})")


def test_what_the_schema_draws_is_refused_by_both(tmp_path):
    """The corpus's schema-drawn cases are refused by the schema by construction; the
    loader must refuse each too (no exemption: they break one value's shape)."""
    drawn = [c for c in CORPUS if c.category == "schema"]
    assert len(drawn) >= 100, len(drawn)
    accepted = []
    for n, case in enumerate(drawn):
        doc, scene, error, errors = compare(case, tmp_path / f"s{n:04d}")
        assert errors, f"{case.ident}: the schema accepts what was drawn to break it"
        if error is None:
            accepted.append(case.ident)
    assert not accepted, accepted[:20]


@pytest.mark.parametrize("reason, exempt", [
    ("unknown material 'x'; defined materials: ash", "cross-reference"),
    ("max must exceed min on every axis; on x: min = 0, max = 0", "geometry"),
    ("must be > 0, got -1", None),
    ("expected a string, got the number 3", None),
    ("unknown key 'x'; allowed keys here: a, b", None),
])
def test_the_exemptions_are_not_a_blanket(reason, exempt, tmp_path):
    """A refusal is exempt only when EXEMPT names it: a range, a type or an unknown key on a
    plain value never is."""
    scene = tmp_path / "scene.toml"
    doc = {"simulation": {"end_time": 1.0}}
    error = SceneError(str(scene), "simulation.end_time", reason)
    assert exemption(error, doc, scene) == exempt


def test_a_quantity_string_is_exempt_only_for_its_value(tmp_path):
    """'1e40 m' matches the length pattern and its value is absurd: exempt. A number out of
    range (the schema has its bounds) is not."""
    scene = tmp_path / "scene.toml"
    absurd = SceneError(str(scene), "simulation.skin", "'1e40 m' is absurd for a length")
    assert exemption(absurd, {"simulation": {"skin": "1e40 m"}}, scene) == "quantity string"
    number = SceneError(str(scene), "simulation.skin", "1e+40 is absurd for a length")
    assert exemption(number, {"simulation": {"skin": 1e40}}, scene) is None


def test_a_disabled_mobility_section_is_still_checked(tmp_path):
    """[mobility] enabled = false with a solid fraction of 5 and an unknown mode: the schema
    refuses it; the loader should too (a key that is wrong is wrong whether used or not)."""
    base = next(b for b in BASES if b.name == "loader_base")
    doc = dict(base.doc, mobility={"enabled": False, "solid_fraction_threshold": 5.0,
                                   "mode": "nope"})
    assert not VALIDATOR.is_valid(schema.json_compatible(doc))
    case = sf.Case("mobility", "mobility", base.name, sf.dumps(doc).encode(), files=base.files)
    with pytest.raises(SceneError):
        load_scene(sf.write_case(case, tmp_path))
