"""The core packages name no effect (issue 46): what an effect does enters the step through
what it declares (effects/base.py ``Effect``), so the engine's code reads neither an effect's
name nor its scene section's. Checked on the code itself - identifiers, attributes, argument
names and string constants - not on docstrings and comments, which may cite an example.

``engine/`` is clean: the contacts' heat is a channel the temperature effect asks for
(``Effect.conducted_field``). So are ``sensors/`` (the walls' and bodies' heat series are the
heat transfer's: thermal/wall_heat_flows.py) and ``recorders/`` (the frames' temperature and
moisture, the viewers' colour and the temperature plots are declared in thermal/settings.py:
FRAME_FIELDS, COLOUR_FIELDS, SERIES_VIEWS). What a fill or a factory gives its particles from an
effect (the temperature, moisture and thermal mass) is the effect's (``Effect.source_values``).
``setup/`` and ``scene/`` are clean too: the keys effects add to the scene's own sections (a
material's conductivity, a wall's temperature, [simulation] gravity) are declared by the effects
(scene/keys.py ``Section.adds``), [thermal] is read like every effect section, the heat's units
are declared by it (thermal/dimensions.py) and the time step asks the effects for their bounds
(gravity's among them). None may come back."""
import ast
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# the identifiers, by core package, that still name an effect (a ratchet: lower it when one
# goes; a new one fails the test)
STILL_NAMED = {"engine": 0, "sensors": 0, "recorders": 0, "setup": 0, "scene": 0}


def _effect_vocabulary() -> set[str]:
    """Every effect's ``name`` and the top-level scene section of every effect settings
    module, each as its words joined by '_' (``wall_conduction``, ``thermal``, ``drag``)."""
    import taichi_dem.effects as effects
    import taichi_dem.thermal as thermal
    from taichi_dem.effects.base import Effect
    from taichi_dem.scene.catalog import settings_modules
    from taichi_dem.scene.keys import Section
    for package in (effects, thermal):
        for m in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            importlib.import_module(m.name)
    names = set()
    pending = [Effect]
    while pending:
        cls = pending.pop()
        pending.extend(cls.__subclasses__())
        if cls is not Effect and isinstance(cls.__dict__.get("name"), str):
            names.add(cls.__dict__["name"])
    declared = [s for module in settings_modules() for value in vars(module).values()
                for s in (value if isinstance(value, (tuple, list)) else (value,))
                if isinstance(s, Section)]
    # (a section nested in another's key, such as the radiation's region, is a table that
    # key reads, not a section of its own)
    nested = {id(n) for s in declared for n in s.nested.values()}
    for s in declared:
        if id(s) not in nested:
            names.add(re.split(r"[.\[]", s.path)[0])
    names.discard("effect")
    return names


def _code_names(path: Path):
    """(line, name) of each identifier, attribute, argument, keyword and string constant in
    ``path``'s code (docstrings left out)."""
    tree = ast.parse(path.read_text(), str(path))
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docstrings.add(id(body[0].value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            yield node.lineno, node.id
        elif isinstance(node, ast.Attribute):
            yield node.lineno, node.attr
        elif isinstance(node, ast.arg):
            yield node.lineno, node.arg
        elif isinstance(node, ast.keyword) and node.arg:
            yield node.lineno, node.arg
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            yield node.lineno, node.name
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str)
              and id(node) not in docstrings):
            yield node.lineno, node.value


def effect_names_in(folder: Path, vocabulary: set[str]) -> list[str]:
    """'file:line: name' for each code name under ``folder`` that contains an effect's name
    or section as whole words ('_'- or '.'-separated: ``temperature_of`` names the
    temperature effect, ``rolling_history`` names none)."""
    patterns = [re.compile(r"(^|[^a-z0-9])" + re.escape(v) + r"($|[^a-z0-9])")
                for v in sorted(vocabulary)]
    out = []
    for path in sorted(folder.rglob("*.py")):
        for line, name in _code_names(path):
            low = name.lower()
            if any(p.search(low) for p in patterns):
                out.append(f"{path.relative_to(folder.parent)}:{line}: {name}")
    return out


@pytest.fixture(scope="module")
def vocabulary():
    return _effect_vocabulary()


def test_the_vocabulary_holds_the_effects_and_their_sections(vocabulary):
    assert {"temperature", "conduction", "wall_conduction", "drying", "radiation", "drag",
            "mobility", "thermal", "gravity", "hertz_mindlin"} <= vocabulary
    assert "rolling" not in vocabulary and "heat" not in vocabulary


@pytest.mark.parametrize("package", sorted(STILL_NAMED))
def test_the_core_names_no_effect(package, vocabulary):
    found = effect_names_in(ROOT / "taichi_dem" / package, vocabulary)
    assert len(found) <= STILL_NAMED[package], "\n".join(found)


def test_the_check_finds_a_named_effect(tmp_path, vocabulary):
    """Not vacuous: each form is caught, and a docstring or a word inside another is not."""
    (tmp_path / "m.py").write_text(
        '"""the temperature effect, in a docstring"""\n'
        "def f(temperature_of, model):\n"
        "    x = model.thermal\n"
        "    y = dict(drag=1)\n"
        "    z = 'mobility'\n"
        "    rolling_history = model.heat\n"
        "    return rolling_history\n")
    found = effect_names_in(tmp_path, vocabulary)
    assert sorted(f.split(": ")[1] for f in found) == ["drag", "mobility", "temperature_of",
                                                       "thermal"], found
