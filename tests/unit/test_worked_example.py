"""docs/architecture.md "Worked example": the effect it shows is the repository's, file for
file, and it touches nothing else. The example's own test (tests/verification/
test_body_force.py, shown in the page too) runs it: its motion against the analytic one, its
series, its bound and its errors."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NAME = "body_force"
# what the repository holds of its own (not builds, caches or environments)
SKIP_DIRS = {".git", ".venv", "build", "dist", "_build", "__pycache__", ".pytest_cache",
             "docs", "node_modules"}
CODE_SUFFIXES = {".py", ".toml", ".cfg", ".txt", ".sh", ".json", ".in"}


def _section() -> str:
    page = (ROOT / "docs" / "architecture.md").read_text()
    start = page.index("## Worked example")
    end = page.index("\n## ", start + 1)
    return page[start:end]


def _shown_files() -> dict[str, str]:
    """{path: text} of every file the example shows in full ("`path`:" and a python block)."""
    blocks = re.findall(r"`([\w/.]+\.py)`:\n\n```python\n(.*?)```\n", _section(), re.S)
    return dict(blocks)


def test_the_page_shows_each_file_as_the_repository_has_it():
    shown = _shown_files()
    assert set(shown) == {f"taichi_dem/effects/{NAME}/__init__.py",
                          f"taichi_dem/effects/{NAME}/settings.py",
                          f"taichi_dem/effects/{NAME}/effect.py",
                          f"tests/verification/test_{NAME}.py"}
    for path, text in shown.items():
        assert (ROOT / path).read_text() == text, f"docs/architecture.md shows an old {path}"


def test_no_other_file_names_the_effect():
    """"Every file it touches": the effect's name appears in no source file but its own
    (no list of effects kept by hand: catalog, registry, schema, units, setup)."""
    mentions = set()
    for path in ROOT.rglob("*"):
        rel = path.relative_to(ROOT)
        if (any(part in SKIP_DIRS or part.endswith(".egg-info") for part in rel.parts)
                or not path.is_file() or path.suffix not in CODE_SUFFIXES
                or path == Path(__file__).resolve()):
            continue
        if NAME in path.read_text(errors="replace"):
            mentions.add(rel.as_posix())
    assert mentions == set(_shown_files()), sorted(mentions)
