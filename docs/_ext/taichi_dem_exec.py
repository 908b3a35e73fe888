"""Executed examples: a ``{exec-python}`` block runs when the docs build, and the page shows
its code followed by what it printed. An exception fails the build.

In a MyST page::

    ```{exec-python}
    from taichi_dem.thermal.correlations import zehner_schlunder
    print(zehner_schlunder(k_solid=2.0, k_gas=0.026, porosity=0.4))
    ```

The blocks of one page share one namespace, in page order (a later block sees an earlier
one's names), and run with the repository root as the working directory (so
``demos/pile.toml`` is found). Options: ``:hide-code:`` shows only the output,
``:hide-output:`` only the code. A page holding a block is read again at every build, so its
examples run every time. Taichi's kernel cache goes to ``TI_OFFLINE_CACHE_FILE_PATH`` when
set (``python3 tasks.py docs`` sets it under the build folder).
"""
from __future__ import annotations

import contextlib
import io
import os
import traceback
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)
ROOT = Path(__file__).resolve().parents[2]


class ExecPython(SphinxDirective):
    has_content = True
    option_spec = {"hide-code": directives.flag, "hide-output": directives.flag}

    def run(self):
        env = self.env
        env.note_reread()           # run again at the next build, changed or not
        source = "\n".join(self.content)
        # temp_data lives while one document is read: one namespace per page
        namespace = env.temp_data.setdefault("exec_python_namespace",
                                             {"__name__": f"docs.{env.docname}"})
        out = io.StringIO()
        cwd = os.getcwd()
        try:
            os.chdir(ROOT)
            with contextlib.redirect_stdout(out):
                exec(compile(source, f"<{env.docname}.md:{self.lineno}>", "exec"), namespace)
        except Exception:           # the page's example is wrong, or the code it shows broke
            failures = env.app.__dict__.setdefault("exec_python_failures", [])
            failures.append(f"{env.docname}:{self.lineno}")
            logger.warning("executed example raised:\n%s", traceback.format_exc(),
                           location=(env.docname, self.lineno), type="exec-python")
            return [nodes.literal_block(source, source, language="python")]
        finally:
            os.chdir(cwd)
        result = []
        if "hide-code" not in self.options:
            result.append(nodes.literal_block(source, source, language="python"))
        text = out.getvalue().rstrip("\n")
        if text and "hide-output" not in self.options:
            block = nodes.literal_block(text, text, language="text")
            block["classes"].append("exec-python-output")
            result.append(block)
        return result


def _check(app, exception) -> None:
    """A failed example fails the build (exit status 1), -W or not."""
    failures = app.__dict__.get("exec_python_failures")
    if exception is None and failures:
        logger.error("%d executed example(s) raised: %s", len(failures), ", ".join(failures))
        app.statuscode = 1


def setup(app):
    app.add_directive("exec-python", ExecPython)
    app.connect("build-finished", _check)
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}
