"""The documentation site names things as a user knows them (issue 48 item 4): no
development labels ("issue 10 item 5", "stop 22") in the pages a user reads, and a source
paper called "seed 00N" only on a page that links the list of sources saying which paper that
is. The benchmark pages record when each figure was measured; they say what their labels
mean at the top."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
DEVELOPMENT = re.compile(r"\b(issue \d+|stop \d+)\b", re.IGNORECASE)
SEED = re.compile(r"\bseed 00\d\b", re.IGNORECASE)
# the pages that record the project's history by its labels (each explains them at the top)
HISTORY = {DOCS / "benchmarks" / "history.md", DOCS / "benchmarks" / "current.md"}


def _pages():
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts or "_generated" in page.parts:
            continue
        yield page


def test_no_development_labels_in_the_pages():
    found = []
    for page in _pages():
        if page in HISTORY:
            continue
        for k, line in enumerate(page.read_text().splitlines(), 1):
            for m in DEVELOPMENT.finditer(line):
                found.append(f"{page.relative_to(ROOT)}:{k}: {m.group(0)}")
    assert not found, found


def test_a_seed_is_named_only_beside_the_list_of_sources():
    unexplained = [str(p.relative_to(ROOT)) for p in _pages()
                   if SEED.search(p.read_text()) and "sources.md" not in p.read_text()
                   and p.name != "sources.md"]
    assert not unexplained, unexplained


def test_the_history_pages_explain_their_labels():
    for page in [DOCS / "benchmarks" / "history.md", ROOT / "BENCHMARKS.md"]:
        head = page.read_text()[:3000]
        assert "stop N" in head and "issue N" in head and "sources.md" in head, page


def test_the_check_catches_a_label():
    assert DEVELOPMENT.search("as issue 10 item 5 asked") and DEVELOPMENT.search("Stop 22")
    assert not DEVELOPMENT.search("the issue is the step") and SEED.search("seed 001's ash")
