"""The generated reference pages (docs/_ext/taichi_dem_reference.py) say what the code declares:
every scene key, every CLI command and option, every results-file dataset with its unit. The
generators run without Sphinx; `python3 tasks.py docs` builds the site around them."""
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def ref():
    path = ROOT / "docs" / "_ext" / "taichi_dem_reference.py"
    spec = importlib.util.spec_from_file_location("taichi_dem_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_scene_key_is_on_the_page(ref):
    from taichi_dem.scene import schema
    written = []
    page = ref.scene_keys_page(written)
    keys = [path for path, _ in schema.every_key()]
    assert sorted(written) == sorted(keys)          # the page walks what the schema walks
    for path in keys:
        assert f"| `{path}` |" in page, path
    # the effects' sections and the mesh builders are there too
    for heading in ("## `[thermal]`", "### `thermal.gas`", "## `[mobility]`", "## `[gas]`",
                    "## `[viscous_damping]`", "### `paddle_shaft`", "## Units"):
        assert heading in page, heading
    row = next(line for line in page.splitlines() if line.startswith("| `simulation.dt` |"))
    assert '"auto"' in row and "`s`" in row


def test_every_command_and_option_is_on_the_page(ref):
    from taichi_dem.app import cli
    written = []
    page = ref.cli_page(written)
    parser = cli._parser()
    commands = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    assert written == list(commands.choices)
    for name, sub in commands.choices.items():
        assert f"## `taichi-dem {name}`" in page, name
        for example in cli.EXAMPLES[name]:
            assert example in page, example
        for action in sub._actions:
            for option in action.option_strings:
                if option not in ("-h", "--help"):
                    assert re.search(rf"`[^`]*{re.escape(option)}\b[^`]*`", page), (name, option)


def test_results_page_names_every_dataset_with_its_unit(ref):
    from taichi_dem.recorders import hdf5
    from taichi_dem.sensors.units import declared
    written = []
    page = ref.results_page(written)
    assert "frames/*/position" in written
    assert "| `position` | `m` | `(N, 3)` |" in page
    for s in declared():
        assert f"| `{s.name}` | `{s.unit}` |" in page, s.name
    assert "| `force` |" not in page      # series keep their full names
    assert "| `bodies/*/force` | `N` | `(samples, 3)` |" in page
    for name in hdf5.RESIDENCE_UNITS:
        assert f"residence/*/{name}" in written


def test_root_attributes_are_declared(ref, tmp_path):
    """Every attribute a results file gets on creation is in ROOT_ATTRIBUTES (the page's
    source), so a new one cannot go undocumented."""
    from taichi_dem.recorders import hdf5
    rec = hdf5.HDF5Recorder(str(tmp_path / "r.h5"), scene_text="", dt=1e-5, arch="cpu",
                            precision="f32")
    rec.close()
    import h5py
    with h5py.File(tmp_path / "r.h5", "r") as f:
        written = set(f.attrs)
    assert written <= set(hdf5.ROOT_ATTRIBUTES), written - set(hdf5.ROOT_ATTRIBUTES)
    assert set(ref.results_page().split("## `/series")[0].count(f"`{a}`") for a in written) == {1}


def test_markdown_escaping(ref):
    assert ref.md("a <stem>_plots | *x*") == r"a \<stem\>\_plots \| \*x\*"
    assert ref.md("see `a_b*` [x]") == r"see `a_b*` \[x\]"
