"""The concurrent search's default memory is the one rule of every build (issue 26 item 3):
asp.heap.memory_budget of its 1 GiB, so a machine with less memory available gets less."""

from __future__ import annotations

from asp import heap
from asp.concurrent.search import DEFAULT_MEMORY, Limits


def test_the_default_memory_follows_the_memory_available(monkeypatch):
    monkeypatch.setattr(heap, "available_memory", lambda: 100 << 30)
    assert Limits().memory == DEFAULT_MEMORY  # plenty: the default itself
    monkeypatch.setattr(heap, "available_memory", lambda: 400 << 20)
    assert Limits().memory == heap.memory_budget() == 300 << 20  # 3/4 of what is there
    assert Limits(memory=5 << 30).memory == 5 << 30  # --max-memory as given
