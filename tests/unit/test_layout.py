"""The layout shows the data flow: no import cycle between modules of taichi_dem, thermal and
geometry, counting imports inside functions too (a function-level import is still a
dependency; it only hides the cycle from Python until the function runs), and geometry stays
plain numpy/trimesh (no taichi_dem, no Taichi)."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# source folder -> the package it installs as (pyproject.toml's package-dir)
PACKAGES = {"taichi_dem": "taichi_dem", "thermal": "taichi_dem.thermal",
            "geometry": "taichi_dem.geometry"}


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return out


def _resolve(name: str, modules) -> str | None:
    """The module of ``modules`` that ``name`` (a dotted module or module.attribute) names."""
    while name:
        if name in modules:
            return name
        name = name.rpartition(".")[0]
    return None


def import_graph() -> dict[str, set[str]]:
    """module -> the modules of the three packages it imports (top level or in a function)."""
    modules = _modules()
    graph = {}
    for mod, path in modules.items():
        is_package = path.name == "__init__.py"
        package = mod if is_package else mod.rpartition(".")[0]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    stem = ".".join(base + ([node.module] if node.module else []))
                else:
                    stem = node.module
                # `from pkg import name`: name may be a submodule or an attribute of pkg
                targets = [f"{stem}.{a.name}" for a in node.names]
            for t in targets:
                hit = _resolve(t, modules)
                if hit is not None and hit != mod:
                    edges.add(hit)
        graph[mod] = edges
    return graph


def cycles(graph) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    found = cycles(import_graph())
    assert not found, "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def test_geometry_is_standalone():
    graph = import_graph()
    for mod, edges in graph.items():
        if mod.startswith("taichi_dem.geometry"):
            assert not [e for e in edges if not e.startswith("taichi_dem.geometry")], (mod, edges)
    for path in (ROOT / "geometry").rglob("*.py"):
        tree = ast.parse(path.read_text())
        names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
        names += [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module]
        assert not [n for n in names if n.split(".")[0] in ("taichi", "taichi_dem")], path


def test_the_cycle_check_sees_cycles():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_exceptions_live_in_errors():
    """Every exception class of taichi_dem is defined in taichi_dem/errors.py."""
    stray = []
    for path in sorted((ROOT / "taichi_dem").rglob("*.py")):
        if path.name == "errors.py" and path.parent.name == "taichi_dem":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                bases = [b.id if isinstance(b, ast.Name) else getattr(b, "attr", "") for b in node.bases]
                if any(b.endswith(("Error", "Exception")) for b in bases):
                    stray.append(f"{path.relative_to(ROOT)}: {node.name}")
    assert not stray, stray


def test_simulation_does_not_import_its_observers_at_module_top():
    """The checkpoint writer and the divergence guard are observers attached when a simulation
    is built, not dependencies of the module."""
    tree = ast.parse((ROOT / "taichi_dem" / "run" / "simulation.py").read_text())
    top = [n.module for n in tree.body if isinstance(n, ast.ImportFrom) and n.module]
    assert not [m for m in top if m.split(".")[-1] in ("checkpoint", "divergence")], top


# docs/architecture.md: no source file over 800 lines, no function over 150, no class holding
# more than 40 attributes - or its docstring says why ("Why ...")
MAX_FILE_LINES, MAX_FUNCTION_LINES, MAX_CLASS_ATTRIBUTES = 800, 150, 40


def _sources():
    for folder in PACKAGES:
        yield from sorted((ROOT / folder).rglob("*.py"))


def test_no_file_function_or_class_is_too_big_unless_it_says_why():
    too_big = []
    for path in _sources():
        text = path.read_text()
        rel = path.relative_to(ROOT)
        if text.count("\n") > MAX_FILE_LINES and "Why this module is over" not in text:
            too_big.append(f"{rel}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES and "Why" not in (ast.get_docstring(node) or ""):
                    too_big.append(f"{rel}: {node.name} has {lines} lines")
            elif isinstance(node, ast.ClassDef):
                stored = {n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)
                          and isinstance(n.value, ast.Name) and n.value.id == "self"
                          and isinstance(n.ctx, ast.Store)}
                if len(stored) > MAX_CLASS_ATTRIBUTES and "Why" not in (ast.get_docstring(node) or ""):
                    too_big.append(f"{rel}: {node.name} holds {len(stored)} attributes")
    assert not too_big, too_big


def package_of(module: str) -> str:
    """The top-level part of taichi_dem a module belongs to ("engine", "scene", "errors")."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "(root)"


def test_packages_import_one_way():
    """docs/architecture.md "Layers": the packages of taichi_dem (engine, scene, effects,
    thermal, ...) import each other without a cycle, so that each stands on a floor above
    everything it imports. (The effects' settings modules and their builders are found by
    discovery and by their sections' declarations, scene/catalog.py and effects/registry.py:
    no import names them.)"""
    packages: dict[str, set[str]] = {}
    why: dict[tuple[str, str], str] = {}
    for module, imported in import_graph().items():
        a = package_of(module)
        packages.setdefault(a, set())
        for other in imported:
            b = package_of(other)
            if a != b:
                packages[a].add(b)
                packages.setdefault(b, set())
                why.setdefault((a, b), f"{module} -> {other}")
    found = cycles(packages)
    assert not found, "packages that import each other in a loop: " + "; ".join(
        " <-> ".join(c) + " (" + ", ".join(why[(x, y)] for x in c for y in c if (x, y) in why)
        + ")" for c in found)
