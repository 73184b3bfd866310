"""Compile the numba kernels once, at install time: ``python -m asmplan.warmup [SOURCE ...]``.

The solvers' hot loops are numba functions cached on disk (``cache=True``, next to their
modules). A fresh checkout has no cache, so its first plan would spend a minute or more of
CPU compiling before it plans (the concurrent search's kernels alone take about 60 s on two
cores). ``make install`` runs this module once: it plans each SOURCE (default: the bundled
examples) with both turn models, in memory, writing nothing but numba's cache, so that every
later ``asmplan`` run starts warm. It prints one line per plan (the steps' progress only
if one fails).
"""

from __future__ import annotations

import contextlib
import io
import sys
import time
from pathlib import Path

DEFAULT_SOURCES = ("examples/vacuum_pump", "examples/vacuum_pump_ranges", "examples/finger_box")
"""The bundled examples: a spec with meshes (alternate and concurrent), duration ranges, and
a CAD folder whose spec plans the concurrent game with alike parts."""


def warm(sources: list[str]) -> None:
    """Plan each source with both turn models, discarding the results.

    Parameters
    ----------
    sources : list of str
        Assembly folders or files (see :func:`asmplan.pipeline.load_assembly`).

    Raises
    ------
    FileNotFoundError
        If a source does not exist (named in the message).
    """
    from asmplan import pipeline
    from asp.concurrent import search

    # the search table's growth (a large product's search outgrows its first table)
    search.table_rehash(search.new_table(16, 1), search.new_table(64, 1))
    for source in sources:
        if not Path(source).exists():
            raise FileNotFoundError(f"warmup: {source}: no such file or folder")
        for turn_model in ("alternate", "concurrent"):
            t0 = time.process_time()
            chatter = io.StringIO()  # the steps' progress, shown only if one fails
            try:
                with contextlib.redirect_stderr(chatter):
                    pipeline.plan(source, turn_model=turn_model, keep_game=False)
            except Exception:
                sys.stderr.write(chatter.getvalue())
                raise
            print(
                f"warmup: {source} ({turn_model}) compiled in {time.process_time() - t0:.0f} s CPU",
                flush=True,
            )


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    warm(args or list(DEFAULT_SOURCES))


if __name__ == "__main__":
    main()
