"""Giving memory back between stages (asp.heap)."""

from __future__ import annotations

import weakref

from asp.heap import map_large_blocks, release_memory


class _Node:
    pass


def test_release_memory_frees_cycles_and_keeps_live_objects():
    cycle, live = _Node(), _Node()
    cycle.me = cycle
    gone = weakref.ref(cycle)
    del cycle
    release_memory()
    assert gone() is None
    assert isinstance(live, _Node)


def test_large_blocks_are_mapped_apart_and_arrays_still_work():
    import numpy as np

    map_large_blocks()
    big = np.arange(1 << 20)  # 8 MB: a block of its own
    assert int(big.sum()) == (1 << 20) * ((1 << 20) - 1) // 2
    del big
    release_memory()
