"""Giving freed memory back to the operating system between the stages of a plan.

A plan of a large assembly goes through stages that each build and drop hundreds of
megabytes: the meshes and collision objects of the part relations, the state graph's layers,
the game's per-edge temporaries. Python and numpy free them, but glibc's allocator keeps
the freed heap pages of small and medium blocks mapped, so the process's resident memory
(what a machine's memory limit counts) stays at the highest it has been.
:func:`release_memory`, called between stages, collects reference cycles and asks glibc to
return free heap pages (``malloc_trim``); on another C library it only collects.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import gc


@functools.cache
def _malloc_trim():
    """glibc's ``malloc_trim``, or None when the C library has none."""
    name = ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name).malloc_trim if name else None
    except (OSError, AttributeError):
        return None


def release_memory() -> None:
    """Collect garbage and return the allocator's free pages to the operating system."""
    gc.collect()
    trim = _malloc_trim()
    if trim is not None:
        trim(0)
