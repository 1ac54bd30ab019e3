"""Where stdout goes for a block: Python's ``sys.stdout`` and the C-level file descriptor 1 alike.

Solvers print below Python (IPOPT and Bonmin through C stdio, SUNDIALS through CasADi), so silencing
them or moving their logs to stderr has to move descriptor 1 itself. One mechanism serves both uses:
the design silences Bonmin (``stdout_to(None)``), the command line sends every log to stderr while its
``--json`` output still reaches the real stdout (``stdout_to(2)`` yields a file on it).
"""

from __future__ import annotations

import ctypes
import os
import sys
from contextlib import contextmanager
from typing import Iterator, TextIO


def _flush_c_stdio() -> None:
    try:  # C stdio buffers: flush them while descriptor 1 still points where they were written for
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


@contextmanager
def stdout_to(target: int | None) -> Iterator[TextIO]:
    """Point stdout at file descriptor ``target`` (None: /dev/null) for the block.

    Yields a text file on the original stdout, for output that must still reach it.
    """
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY) if target is None else None
    os.dup2(null if target is None else target, 1)
    python_stdout = sys.stdout
    sys.stdout = os.fdopen(os.dup(1), "w")
    original = os.fdopen(os.dup(saved), "w")
    try:
        yield original
    finally:
        _flush_c_stdio()
        sys.stdout.flush()
        sys.stdout.close()
        sys.stdout = python_stdout
        original.flush()
        original.close()
        os.dup2(saved, 1)
        os.close(saved)
        if null is not None:
            os.close(null)
