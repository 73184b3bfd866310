"""The ``asmplan`` command line.

The CLI sits on top of all three packages (``cad`` <- ``asp`` <- ``arl`` <- CLI), so it lives
in the top package. Each command group is a module of its own that registers on the one
Typer app; heavy libraries (torch, OR-Tools, trimesh) are imported inside the commands so
that ``asmplan solve`` starts fast.
"""

from asmplan.cli.app import app, main

# Importing a command module registers its commands on ``app``.
from asmplan.cli import core as _core  # noqa: F401, E402  isort: skip
from asmplan.cli import cad as _cad  # noqa: F401, E402  isort: skip
from asmplan.cli import assembly as _assembly  # noqa: F401, E402  isort: skip
from asmplan.cli import init as _init  # noqa: F401, E402  isort: skip
from asmplan.cli import train as _train  # noqa: F401, E402  isort: skip
from asmplan.cli import play as _play  # noqa: F401, E402  isort: skip
from asmplan.cli import experiment as _experiment  # noqa: F401, E402  isort: skip

__all__ = ["app", "main"]
