"""The exception family users catch: every library error for bad input is an ``AsmplanError``.

Example
-------
>>> from asmplan.errors import AsmplanError
>>> from asmplan import pipeline
>>> try:
...     pipeline.load_assembly("no/such/folder")
... except (AsmplanError, OSError) as exc:
...     print(exc)
no/such/folder: no such file or folder
"""

from asp.errors import (
    AsmplanError,
    FormatError,
    GameError,
    GameLimit,
    GeometryError,
    GraphError,
    InfeasibleAssembly,
    Interpenetration,
    ScheduleError,
    SpecError,
    StateLimit,
)

__all__ = [
    "AsmplanError",
    "FormatError",
    "GameError",
    "GameLimit",
    "GeometryError",
    "GraphError",
    "InfeasibleAssembly",
    "Interpenetration",
    "ScheduleError",
    "SpecError",
    "StateLimit",
]
