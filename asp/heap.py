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

And the one rule of how much memory a build may use (:func:`memory_budget`: a share of the
memory available when it starts), which every builder with a memory bound calls.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import gc
import os

LARGE_BLOCK = 1 << 20
"""Blocks of at least this many bytes (1 MiB) are mapped on their own
(:func:`map_large_blocks`)."""

MEMORY_SHARE = 0.75
"""A build may use at most this share of the memory available when it starts
(:func:`memory_budget`)."""

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


def available_memory() -> int:
    """Bytes of memory available now: ``MemAvailable`` of ``/proc/meminfo`` (else the free
    physical pages, else 8 GiB), and no more than the process's control group leaves
    (:func:`cgroup_room`)."""
    free = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    free = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    if free is None:
        try:
            free = int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES"))
        except (AttributeError, ValueError, OSError):
            free = 8 << 30
    room = cgroup_room()
    return free if room is None else min(free, room)


CGROUP_FILES = (
    ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
    ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"),
)
"""The memory limit and usage of the process's control group (v2, then v1)."""


def cgroup_room(files=CGROUP_FILES) -> int | None:
    """Bytes the control group's memory limit leaves (limit minus usage), or None when
    there is no limit (``max``, or v1's huge number) or no such files."""
    for limit_file, usage_file in files:
        try:
            with open(limit_file, encoding="ascii") as f:
                limit = f.read().strip()
            with open(usage_file, encoding="ascii") as f:
                usage = int(f.read().strip())
        except (OSError, ValueError):
            continue
        if limit == "max" or not limit.isdigit() or int(limit) >= 1 << 60:
            return None
        return max(0, int(limit) - usage)
    return None


def memory_budget(cap: int | None = None) -> int:
    """The bytes a build may use: :data:`MEMORY_SHARE` of :func:`available_memory`, and at
    most ``cap`` bytes when given."""
    share = int(MEMORY_SHARE * available_memory())
    return share if cap is None else min(int(cap), share)


__all__ = [
    "available_memory",
    "map_large_blocks",
    "memory_budget",
    "release_memory",
]
"""What other modules may use (asmplan and arl among them)."""
