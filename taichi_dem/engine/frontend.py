"""Three savings in Taichi 1.7's Python front end, which turns every kernel and ``ti.func`` into
Taichi IR each time a simulation is built (Taichi's compiled-kernel cache cannot be used for
that step: its key is computed from the IR).

A simulation compiles ~35-60 kernels, and its build time (BENCHMARKS.md, "Stop 22 ...: where the
suite's time goes") went, on a 200-particle scene (cProfile), about 2.0 s of 5.4 s to two things that do not
depend on the simulation:

1. **The source of each function**, read again and re-indented for every instantiation
   (``inspect.getsourcelines`` tokenises the whole file): here kept per code object, so each
   function's source is read once per process, and on disk (setup/memo.py's folder, keyed by
   the file's path and contents), so once per version of its file. ``ast.parse`` still runs
   every time (Taichi writes into the tree it transforms).
2. **The position text of each statement** (``ASTTransformerContext.get_pos_info``): the file,
   line and function, the source line and a ``^^^`` marker under the expression, for the
   message of a compile error. Taichi wrote it, wrapped at 80 columns with ``textwrap``, for
   every node of every kernel (~22,000 calls for the main demo's step alone, ~0.08 s of its
   start) into the IR's debug information, which only debug-mode runtime checks read; here it
   is written only for a compile error's message (unwrapped: the same file, line and
   expression), and the debug information gets "".
3. **Whether ``@ti.kernel`` decorates a method in a class body**, which Taichi reads from the
   caller's source line (~0.3 ms a kernel, ~370 kernels defined per simulation, ~0.1 s of the
   main demo's start): here from the caller frame's namespace (``_quick_class_test``).

All three keep Taichi's behaviour otherwise; they are applied only to the Taichi versions they
were written against (1.7.x) and not at all with ``TAICHI_DEM_PLAIN_TAICHI=1`` in the
environment.
"""
from __future__ import annotations

import ast
import os
import textwrap

import taichi as ti

_applied: list = []


def applies() -> bool:
    """Whether the savings are (to be) applied: Taichi 1.7.x and not switched off."""
    return tuple(ti.__version__[:2]) == (1, 7) and os.environ.get("TAICHI_DEM_PLAIN_TAICHI", "") in ("", "0")


def apply() -> bool:
    """Install both savings once per process; returns whether they are installed."""
    if _applied:
        return _applied[0]
    ok = applies()
    if ok:
        try:
            _cache_sources()
            _plain_positions()
            _quick_class_test()
        except (ImportError, AttributeError):     # a 1.7.x whose internals differ: leave it
            ok = False
    _applied.append(ok)
    return ok


def _cache_sources() -> None:
    from taichi.lang import kernel_impl as k
    from taichi.lang.ast import ASTTransformerContext

    original = k._get_tree_and_ctx
    sources: dict = {}

    def source_of(func):
        """(file, re-indented lines, first line number, dedented text) of ``func``, read
        once per code object (Taichi's reading, unchanged)."""
        code = getattr(func, "__code__", None)
        if code is None:
            return None
        found = sources.get(code)
        if found is None:
            found = _stored_source(code)
            if found is None:
                file = k.getsourcefile(func)
                src, start_lineno = k.getsourcelines(func)
                src = [textwrap.fill(line, tabsize=4, width=9999) for line in src]
                found = (file, src, start_lineno, textwrap.dedent("\n".join(src)))
                _store_source(code, found)
            sources[code] = found
        return found

    def get_tree_and_ctx(self, excluded_parameters=(), is_kernel=True, arg_features=None,
                         args=None, ast_builder=None, is_real_function=False):
        found = source_of(self.func)
        if found is None:
            return original(self, excluded_parameters, is_kernel, arg_features, args,
                            ast_builder, is_real_function)
        file, src, start_lineno, text = found
        tree = ast.parse(text)          # a new tree each time: the transform writes into it
        tree.body[0].decorator_list = []
        global_vars = k._get_global_vars(self.func)
        if is_kernel or is_real_function:
            for i in self.template_slot_locations:
                global_vars[self.arguments[i].name] = args[i]
        return tree, ASTTransformerContext(
            excluded_parameters=excluded_parameters, is_kernel=is_kernel, func=self,
            arg_features=arg_features, global_vars=global_vars, argument_data=args,
            src=src, start_lineno=start_lineno, file=file, ast_builder=ast_builder,
            is_real_function=is_real_function)

    k._get_tree_and_ctx = get_tree_and_ctx


_file_digests: dict = {}


def _source_path(code):
    """Where the source of ``code`` is kept on disk (setup/memo.py's folder), keyed by its
    file's path and contents (a digest, once per file and process), its first line and name;
    None without a cache or a file."""
    import hashlib
    from ..setup.memo import cache_dir
    folder = cache_dir()
    if folder is None:
        return None
    digest = _file_digests.get(code.co_filename)
    if digest is None:
        try:
            with open(code.co_filename, "rb") as f:
                digest = hashlib.sha256(f.read()).hexdigest()
        except (OSError, TypeError):
            return None
        _file_digests[code.co_filename] = digest
    # (co_qualname is Python 3.11's; 3.10 has the name only, with the first line beside it)
    key = repr((code.co_filename, digest, code.co_firstlineno,
                getattr(code, "co_qualname", code.co_name)))
    return folder / "sources" / (hashlib.sha256(key.encode()).hexdigest()[:32] + ".pkl"), key


def _stored_source(code):
    """The source of ``code`` as ``source_of`` read it in an earlier process, or None: reading
    it (Taichi tokenises the file up to the function and scans sys.modules for its module)
    took ~0.15 s of the main demo's start."""
    import pickle
    found = _source_path(code)
    if found is None:
        return None
    path, key = found
    try:
        with open(path, "rb") as f:
            stored_key, value = pickle.load(f)
        return value if stored_key == key else None
    except Exception:            # absent, damaged or unreadable: read the source
        return None


def _store_source(code, value) -> None:
    import pickle
    import tempfile
    found = _source_path(code)
    if found is None:
        return
    path, key = found
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            pickle.dump((key, value), f)
        os.replace(tmp, path)
    except Exception:            # a read-only or full disk: the source is still right
        pass


def _plain_positions() -> None:
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    def get_pos_info(self, node):
        """Taichi's position text (file, line, function, the source lines with ^^^ under
        the expression), without wrapping at 80 columns."""
        msg = (f'File "{self.file}", line {node.lineno + self.lineno_offset}, '
               f'in {self.func.func.__name__}:\n')
        col_offset = self.indent + node.col_offset
        end_col_offset = self.indent + node.end_col_offset
        src = self.src
        if node.lineno == node.end_lineno:
            line = src[node.lineno - 1]
            return msg + line + "\n" + " " * col_offset + "^" * (end_col_offset - col_offset) + "\n"
        if node.__class__.__name__ in ("For", "While", "FunctionDef", "If"):
            end_lineno = max(node.body[0].lineno - 1, node.lineno)
        else:
            end_lineno = node.end_lineno
        for i in range(node.lineno - 1, end_lineno):
            line = src[i]
            body = line.rstrip()
            first = len(line) - len(line.lstrip())
            last = len(body)
            if i == node.lineno - 1:
                hint = " " * col_offset + "^" * (last - col_offset)
            elif i == node.end_lineno - 1:
                hint = " " * first + "^" * (end_col_offset - first)
            elif first < last:
                hint = " " * first + "^" * (last - first)
            else:
                hint = ""
            msg += line + "\n" + hint + "\n"
        return msg

    # the position text is wanted only in a compile error's message (Builder's except path);
    # every other caller stores it in the IR's debug information, read by debug-mode runtime
    # checks, which this package does not use: those get "" (22,000 calls for the main demo)
    from taichi.lang import impl
    from taichi.lang.ast import ast_transformer_utils as utils
    from taichi.lang.exception import (TaichiCompilationError, TaichiSyntaxError,
                                       handle_exception_from_cpp)

    def no_position(self, node):
        return ""

    ASTTransformerContext.get_pos_info = no_position
    ASTTransformerContext.position_text = get_pos_info

    def build(self, ctx, node):
        method = getattr(self, "build_" + node.__class__.__name__, None)
        try:
            if method is None:
                raise TaichiSyntaxError(f'Unsupported node "{node.__class__.__name__}"')
            return method(ctx, node)
        except Exception as e:
            if impl.get_runtime().print_full_traceback:
                raise e
            if ctx.raised or not isinstance(node, (ast.stmt, ast.expr)):
                raise e.with_traceback(None)
            ctx.raised = True
            e = handle_exception_from_cpp(e)
            if not isinstance(e, TaichiCompilationError):
                import traceback
                raise TaichiCompilationError(ctx.position_text(node) + traceback.format_exc()) from None
            raise type(e)(ctx.position_text(node) + str(e)) from None

    utils.Builder.__call__ = build

    def current_position(self):
        """The debug information's position: "" (nothing pushes positions now)."""
        return self.src_info_stack[-1] if self.src_info_stack else ""

    impl.PyTaichi.get_current_src_info = current_position


def _quick_class_test() -> None:
    """``@ti.kernel`` asks whether it decorates a method in a class body
    (``kernel_impl._inside_class``) by reading the source line of the calling frame
    (``inspect.getframeinfo``: the module found by scanning ``sys.modules``, the file read
    through linecache), ~0.3 ms a kernel, and a simulation defines ~370 kernels (~0.1 s of the
    main demo's start). A class body's frame is known by its namespace, which Python gives
    ``__module__`` and ``__qualname__`` before the body runs: the same answer, from the frame."""
    from taichi.lang import impl, kernel_impl as k, snode, util

    from .._taichi_hooks import declaration_trace, inside_class
    k._inside_class = inside_class
    # (and the fields' declaration trace, without source lines: _taichi_hooks.py)
    util.get_traceback = impl.get_traceback = snode.get_traceback = declaration_trace
