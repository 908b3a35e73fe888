"""Effects see the model and the state, never the engine or the raw scene (issue 30): every
effect method gets an ``EffectContext`` (effects/base.py), which shows only what it lists and
refuses to be written to; and no effect module names the engine, reads ``.scene`` or writes
an attribute onto what it is handed. (Effects read their scene settings from the arguments
their constructors get in effects/registry.py and thermal/effects.py ``thermal_effects``.)"""
import ast
from pathlib import Path

import pytest

from taichi_dem.effects.base import EffectContext

ROOT = Path(__file__).resolve().parents[2]
EFFECT_MODULES = sorted(set((ROOT / "taichi_dem" / "effects").rglob("*.py"))
                        - {ROOT / "taichi_dem" / "effects" / "base.py",
                           ROOT / "taichi_dem" / "effects" / "registry.py"}) + [
    ROOT / "thermal" / "effects.py", ROOT / "thermal" / "radiation.py"]
# the methods through which the engine calls an effect: their first argument is the context
HOOKS = {"allocate", "upload", "contact_func", "particle_func", "integrate_func", "cell_func",
         "after_pairs", "compile", "update", "prepare", "after_rebuild", "make_rigid_drift", "make_rigid_velocity",
         "make_rigid_centre", "make_rigid_spin", "frame_reach", "fraction_within",
         "_compile_cells", "_tabulate", "_allocate_tables", "_ratios", "_upload_volumes"}


def _violations(path: Path, root: Path = ROOT) -> list[str]:
    tree = ast.parse(path.read_text(), str(path))
    out = []
    rel = path.relative_to(root)
    for node in ast.walk(tree):
        if isinstance(node, ast.arg) and node.arg == "engine":
            out.append(f"{rel}:{node.lineno}: a parameter named 'engine'")
        if isinstance(node, ast.Name) and node.id == "engine":
            out.append(f"{rel}:{node.lineno}: the name 'engine'")
        if isinstance(node, ast.Attribute) and node.attr in ("scene", "_engine"):
            out.append(f"{rel}:{node.lineno}: reads .{node.attr}")
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name) \
                        and t.value.id == "ctx":
                    out.append(f"{rel}:{node.lineno}: writes ctx.{t.attr}")
        if isinstance(node, ast.FunctionDef) and node.name in HOOKS:
            args = [a.arg for a in node.args.args]
            first = args[1] if args and args[0] == "self" else (args[0] if args else None)
            if first not in (None, "ctx", "n", "grid"):
                out.append(f"{rel}:{node.lineno}: {node.name}'s first argument is {first!r}, "
                           "not the context")
    return out


def test_the_effect_modules_are_found():
    names = {p.name for p in EFFECT_MODULES}
    assert {"effect.py", "effects.py", "hertz_mindlin.py", "rolling.py"} <= names
    assert any(p.parent.name == "gravity" and p.name == "effect.py" for p in EFFECT_MODULES)


@pytest.mark.parametrize("path", EFFECT_MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_effect_touches_the_engine_or_the_scene(path):
    assert _violations(path) == []


def test_the_check_catches_each_kind_of_violation(tmp_path):
    """The static check above is not vacuous: each forbidden form is caught."""
    bad = tmp_path / "bad.py"
    bad.write_text("class E:\n"
                   "    def allocate(self, engine, tree):\n"
                   "        engine.gas_stream = 1\n"
                   "    def upload(self, ctx):\n"
                   "        ctx.emissivity = ctx.scene.materials\n"
                   "        x = ctx._engine\n")
    found = "\n".join(_violations(bad, tmp_path))
    for what in ("parameter named 'engine'", "the name 'engine'", "reads .scene",
                 "writes ctx.emissivity", "reads ._engine"):
        assert what in found, what


class _FakeModel:
    real, dt, grid = "f64", 1e-5, "grid"
    scene = "the raw scene"
    effect_list = ()

    def effect(self, name):
        return None


class _FakeStep:
    serial = True
    scene = "the raw scene"


def test_the_context_shows_only_the_model_and_the_state():
    ctx = EffectContext(_FakeModel(), "values", {"friction": "table"}, "state", _FakeStep())
    assert ctx.dt == 1e-5 and ctx.state == "state" and ctx.serial is True
    assert ctx.table["friction"] == "table" and ctx.broadphase is None
    with pytest.raises(AttributeError, match="not 'scene'"):
        ctx.scene                    # (the model and the step have one: not shown)
    with pytest.raises(AttributeError, match="not 'effect_list'"):
        ctx.effect_list
    with pytest.raises(AttributeError, match="cannot set"):
        ctx.gas_stream = object()
    ctx.attach("broadphase", "cells")
    assert ctx.broadphase == "cells"
    assert ctx.effect("drag") is None
