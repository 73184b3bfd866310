"""The ``asmplan`` command line.

The CLI sits on top of all three packages (``cad`` <- ``asp`` <- ``arl`` <- CLI), so it lives
in the top package. Each command is a module of its own (``asmplan/cli/<command>.py``) that
registers on the one Typer app (:mod:`asmplan.cli.app`, which also holds the error policy)
and calls :mod:`asmplan.pipeline` for the work; option ranges and choices shared by several
commands are in :mod:`asmplan.cli.options`. Heavy libraries (torch, OR-Tools, trimesh) are
imported inside the commands so that ``asmplan solve`` starts fast.
"""

from asmplan.cli.app import app, main

# Importing a command module registers its commands on ``app``.
from asmplan.cli import synth as _synth  # noqa: F401, E402  isort: skip
from asmplan.cli import solve as _solve  # noqa: F401, E402  isort: skip
from asmplan.cli import relations as _relations  # noqa: F401, E402  isort: skip
from asmplan.cli import graph as _graph  # noqa: F401, E402  isort: skip
from asmplan.cli import baseline as _baseline  # noqa: F401, E402  isort: skip
from asmplan.cli import plan as _plan  # noqa: F401, E402  isort: skip
from asmplan.cli import report as _report  # noqa: F401, E402  isort: skip
from asmplan.cli import init as _init  # noqa: F401, E402  isort: skip
from asmplan.cli import train as _train  # noqa: F401, E402  isort: skip
from asmplan.cli import play as _play  # noqa: F401, E402  isort: skip
from asmplan.cli import experiment as _experiment  # noqa: F401, E402  isort: skip
from asmplan.cli import serve as _serve  # noqa: F401, E402  isort: skip
from asmplan.cli import study as _study  # noqa: F401, E402  isort: skip

__all__ = ["app", "main"]
