"""Giving freed memory back to the operating system during a plan.

A plan of a large assembly goes through stages that each build and drop hundreds of
megabytes: the meshes and collision objects of the part relations, the state graph's layers,
the game's per-edge temporaries. Python and numpy free them, but glibc's allocator keeps
freed heap pages mapped, so the process's resident memory (what a machine's memory limit
counts) stays at the highest it has been. Two remedies, both only on glibc (elsewhere they
do nothing but collect garbage):

- :func:`map_large_blocks`: every block of at least :data:`LARGE_BLOCK` bytes is mapped on
  its own and unmapped when freed. glibc does this by default only from a threshold it
  raises as the program frees large blocks (up to 32 MiB), after which arrays of a few
  megabytes stay in the heap once freed.
- :func:`release_memory`, called between stages: collects reference cycles and returns the
  heap's free pages (``malloc_trim``).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import gc

LARGE_BLOCK = 1 << 20
"""Blocks of at least this many bytes (1 MiB) are mapped on their own
(:func:`map_large_blocks`)."""

_M_MMAP_THRESHOLD = -3
"""glibc's ``mallopt`` parameter of the mapping threshold (``malloc.h``)."""


@functools.cache
def _glibc():
    """The C library when it is glibc (has ``malloc_trim`` and ``mallopt``), else None."""
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name) if name else None
        return libc if libc is not None and libc.malloc_trim and libc.mallopt else None
    except (OSError, AttributeError):
        return None


def map_large_blocks() -> None:
    """Map every block of at least :data:`LARGE_BLOCK` bytes on its own, so that freeing it
    gives it back to the operating system at once (for the rest of the process)."""
    libc = _glibc()
    if libc is not None:
        libc.mallopt(_M_MMAP_THRESHOLD, LARGE_BLOCK)


def release_memory() -> None:
    """Collect garbage and return the allocator's free pages to the operating system."""
    gc.collect()
    libc = _glibc()
    if libc is not None:
        libc.malloc_trim(0)
