"""Files written so that a run killed at any moment leaves whole files behind: the side files
(temporaries, mirrors) a writer keeps beside its output, and their clean-up."""
from __future__ import annotations

import os


def side_path(path: str, tag: str) -> str:
    """The hidden file beside ``path`` that this process uses for ``tag`` ("tmp", "mirror",
    ...): ``.<name>.<pid>.<tag>`` in the same folder, so that ``os.replace`` onto ``path`` is
    a rename within one file system (atomic on POSIX)."""
    directory, base = os.path.split(os.path.abspath(path))
    return os.path.join(directory, f".{base}.{os.getpid()}.{tag}")


def remove_stale_side_files(path: str, tags: tuple[str, ...] = ("tmp",)) -> None:
    """Remove the side files of ``path`` (``side_path``) left by writers that were killed
    mid-write: those whose process is gone. A live writer's files are left alone."""
    directory, base = os.path.split(os.path.abspath(path))
    prefix = f".{base}."
    if not os.path.isdir(directory):
        return
    for name in os.listdir(directory):
        if not name.startswith(prefix):
            continue
        pid, _, tag = name[len(prefix):].partition(".")
        if tag not in tags or not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            try:
                os.unlink(os.path.join(directory, name))
            except OSError:
                pass
        except OSError:          # alive, but not ours to signal
            pass
