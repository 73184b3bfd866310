"""The concurrent search's default memory is the one rule of every build (issue 26 item 3):
asp.heap.memory_budget of its 1 GiB, so a machine with less memory available gets less."""

from __future__ import annotations

import time

import pytest

from asp import heap
from asp.concurrent.search import DEFAULT_MEMORY, Limits


def test_the_default_memory_follows_the_memory_available(monkeypatch):
    monkeypatch.setattr(heap, "available_memory", lambda: 100 << 30)
    assert Limits().memory == DEFAULT_MEMORY  # plenty: the default itself
    monkeypatch.setattr(heap, "available_memory", lambda: 400 << 20)
    assert Limits().memory == heap.memory_budget() == 300 << 20  # 3/4 of what is there
    assert Limits(memory=5 << 30).memory == 5 << 30  # --max-memory as given


@pytest.mark.parametrize(
    ("work_seconds", "after", "said"),
    [(0.3, 0.01, 1), (0.0, 10.0, 0)],
    ids=["slow compile is said once", "a cache load says nothing"],
)
def test_a_long_kernel_compile_is_said_once(work_seconds, after, said):
    from asp.concurrent.search import COMPILE_NOTE, with_note

    lines: list[str] = []
    with_note(lambda: time.sleep(work_seconds), after, lines.append)
    time.sleep(0.05)  # a timer that was cancelled never says it later
    assert lines == [COMPILE_NOTE] * said
