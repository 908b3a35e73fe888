"""Ctrl-C in a run from the command line, honoured where the state is whole.

Python's own handler raises KeyboardInterrupt at whatever bytecode the main thread runs next.
Inside a finaliser (``__del__``, a C extension's deallocation: h5py's objects, Taichi's) the
exception cannot propagate: Python prints "Exception ignored" and drops it, and the run went
on as if Ctrl-C had not been pressed (a test that interrupts the pile demo hung now and then).
Landing in the middle of ``Simulation.step`` it also left the simulation's clock behind its
engine. Here the first Ctrl-C only sets a flag, which ``Simulation.step`` reads after each
chunk of steps (at most an output interval) and turns into KeyboardInterrupt there; a second
Ctrl-C raises at once, as Python's handler would.
"""
from __future__ import annotations

import os
import signal
import threading

_requested = False


def _handler(signum, frame):
    global _requested
    if _requested:                      # the second Ctrl-C: at once
        raise KeyboardInterrupt
    _requested = True
    # (os.write: safe where print may be re-entered)
    os.write(2, b"\ntaichi-dem: stopping at the end of this chunk of steps "
                b"(Ctrl-C again to stop at once)\n")


def check() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed since the last check (inside
    ``deferred``); Simulation.step calls it between its chunks of steps."""
    global _requested
    if _requested:
        _requested = False
        raise KeyboardInterrupt


class deferred:
    """``with deferred(): sim.run(...)``: Ctrl-C stops the run at the next chunk boundary (see
    the module docstring). Only on the main thread (signals are delivered there); elsewhere a
    no-op."""

    def __enter__(self):
        global _requested
        _requested = False
        self.previous = None
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, _handler)
        return self

    def __exit__(self, *exc):
        global _requested
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        _requested = False
        return False
