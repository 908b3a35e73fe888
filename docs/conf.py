"""Sphinx configuration of the taichi_dem documentation (python3 tasks.py docs builds it).

The pages are Markdown (MyST-parser); the Python API comes from the docstrings (autodoc); the
reference pages on scene keys, the CLI and the results file are generated from the code's
declarations at every build (_ext/taichi_dem_reference.py), and ``{exec-python}`` blocks run
while the pages are read (_ext/taichi_dem_exec.py). See about_docs.md.
"""
import os
import sys
from pathlib import Path

# no Taichi banner in the build's output (the API page imports taichi_dem.run.simulation)
os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "False")

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))     # taichi_dem from the checkout, installed or not

from taichi_dem import __version__  # noqa: E402

project = "taichi_dem"
author = "taichi_dem contributors"
copyright = "taichi_dem contributors, Apache-2.0"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "taichi_dem_reference",
    "taichi_dem_exec",
]
source_suffix = {".md": "markdown"}
root_doc = "index"

# pages that are not part of the site on their own: the generated references (included by the
# stubs in reference/), the machine's headingless tables (included by machine/tables.md), the
# build output
exclude_patterns = ["_build", "reference/_generated", "machine/seed_cooler/seed_table.md",
                    "machine/seed_cooler/free_rolling/seed_table.md",
                    "machine/direct_check/comparison_6rows.md",
                    "machine/direct_rtd/comparison.md",
                    "machine/modelling_choices/choices.md",
                    # the seed's modelling-choice maps: summed up by their choices.md and
                    # precision_long.md, which machine/tables.md includes
                    "machine/seed_cooler/free_rolling/modelling_choices/*/map.md",
                    "machine/seed_cooler/free_rolling/modelling_choices/*.md",
                    "machine/seed_cooler/free_rolling/modelling_choices_optimised/*/map.md",
                    "machine/seed_cooler/free_rolling/modelling_choices_optimised/*.md",
                    # the maps behind the full-shell and stagger pages, which sum them up
                    "machine/seed_cooler/full_shell/map_*/map.md",
                    "machine/seed_cooler/size/*/map.md",
                    "machine/seed_cooler/stagger/*/map.md"]

myst_enable_extensions = ["colon_fence", "deflist"]
# `## Heading` gets an anchor, so [text](page.md#heading) links resolve
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}

html_theme = "furo"
html_title = f"taichi_dem {__version__}"
html_static_path = []


# the content folders are globbed by index.md's tables of contents and may be empty while their
# pages are being written; Sphinx warns of a glob that matches nothing (a warning without a type,
# so suppress_warnings cannot silence it), so such a folder's line is left out of the source
GLOBBED = ("tutorials", "howto", "explanation", "benchmarks", "reference")


def _drop_empty_globs(app, docname, source):
    if docname != "index":
        return
    for folder in GLOBBED:
        if not any((DOCS / folder).glob("*.md")):
            source[0] = source[0].replace(f"\n{folder}/*\n", "\n")


def setup(app):
    app.connect("source-read", _drop_empty_globs)
