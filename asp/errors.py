"""Planning errors: the :class:`~cad.errors.AsmplanError` family extended for ``asp``.

=====================  ====================================================================
class                  raised for
=====================  ====================================================================
``SpecError``          an assembly specification (``assembly.yaml``, ``.IN2``) that is wrong
``GraphError``         a game DAG (file or arrays) that is malformed or not a valid game
``GameError``          a move, policy or session request the game does not allow
``ScheduleError``      a scheduling problem (``.sm``, CP-SAT baseline) that cannot be built
``FormatError``        a file in one of the readers' formats that does not parse
=====================  ====================================================================
"""

from __future__ import annotations

from cad.errors import AsmplanError, GeometryError


class SpecError(AsmplanError):
    """An assembly specification that is malformed or inconsistent."""


class GraphError(AsmplanError):
    """A game DAG that is malformed, cyclic, or has no valid start and end."""


class GameError(AsmplanError):
    """A move, a policy or a play request the rules of the game do not allow."""


class ScheduleError(AsmplanError):
    """A scheduling problem that cannot be built or solved as asked."""


class FormatError(AsmplanError):
    """A data file (``.IN2``, ``.sm``, JSON, GraphML) that does not parse."""


__all__ = [
    "AsmplanError",
    "FormatError",
    "GameError",
    "GeometryError",
    "GraphError",
    "ScheduleError",
    "SpecError",
]
