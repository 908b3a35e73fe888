"""Every /series name the code writes is declared with its unit (sensors/series.py, and the
effects' SERIES in their settings modules): a static check over the modules that write
series (each string literal or f-string pattern they assign into ``values[...]`` or return as
a series name), so a new series without a unit fails here before any run. The results file's
``units`` attributes are checked on a live run in tests/verification/test_process.py."""
import ast
from pathlib import Path

import pytest

from taichi_dem.sensors.units import declared, describe, unit_of

ROOT = Path(__file__).resolve().parents[2]
WRITERS = [ROOT / "taichi_dem" / "sensors" / n for n in
           ("particles.py", "loads.py", "mass_flow.py", "residence.py", "contacts.py")] + [
    ROOT / "thermal" / "energy_balance.py", ROOT / "thermal" / "wall_heat_flows.py",
    ROOT / "taichi_dem" / "process" / "accounting.py",
    ROOT / "taichi_dem" / "process" / "factories.py",
    ROOT / "thermal" / "plug_flow.py",
    # the heat effects' ``sample``: the mean temperature, the drying's, the radiation's
    ROOT / "thermal" / "effects.py", ROOT / "thermal" / "radiation.py"] + sorted(
    # an effect's ``sample`` writes its own series
    (ROOT / "taichi_dem" / "effects").glob("*/effect.py"))


def _pattern(node, prefixes) -> str | None:
    """The series name a subscript key or dict key stands for, "*" for formatted parts."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "*" for v in node.values)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add) \
            and isinstance(node.left, ast.Name) and node.left.id in prefixes:
        tail = _pattern(node.right, prefixes)
        return prefixes[node.left.id] + tail if tail is not None else None
    return None


def written_series() -> set[str]:
    names = set()
    for path in WRITERS:
        tree = ast.parse(path.read_text(), str(path))
        prefixes = {}
        for node in ast.walk(tree):
            # p = f"outlets/{out.name}/" and the like
            if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                    and isinstance(node.targets[0], ast.Name):
                value = _pattern(node.value, {})
                if value is not None and value.endswith("/"):
                    prefixes[node.targets[0].id] = value
        for node in ast.walk(tree):
            keys = []
            if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) \
                    and isinstance(node.value, ast.Name) and node.value.id in ("values", "thermal"):
                keys = [node.slice]
            elif isinstance(node, ast.Dict):
                keys = [k for k in node.keys if k is not None]
            for k in keys:
                name = _pattern(k, prefixes)
                if name is not None and "/" in name:
                    names.add(name)
    return names


def test_the_writers_are_read():
    names = written_series()
    assert {"particles/count", "bodies/*/axial_torque", "outlets/*/mass_flow",
            "gas/drag_force", "gas/temperature", "sensors/*/p90"} <= names


@pytest.mark.parametrize("name", sorted(written_series()))
def test_every_written_series_has_a_unit(name):
    assert unit_of(name.replace("*", "x")), f"{name}: no declaration (sensors/series.py or an effect's SERIES)"


def test_declarations_are_unique_and_described():
    patterns = [s.name for s in declared()]
    assert len(patterns) == len(set(patterns))
    assert all(s.unit and s.description for s in declared())
    assert unit_of("time") == "s" and unit_of("bodies/shaft/axial_torque") == "N m"
    assert unit_of("no/such/series") is None and describe("gas/drag_force")
