"""Giving memory back between stages (asp.memory)."""

from __future__ import annotations

import weakref

from asp.memory import release_memory


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
