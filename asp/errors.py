"""Planning errors: the :class:`~cad.errors.AsmplanError` family extended for ``asp``.

=====================  ====================================================================
class                  raised for
=====================  ====================================================================
``SpecError``          an assembly specification (``assembly.yaml``, ``.IN2``) that is wrong
``GraphError``         a game DAG (file or arrays) that is malformed or not a valid game
``GameError``          a move, policy or session request the game does not allow
``ScheduleError``      a scheduling problem (``.sm``, CP-SAT baseline) that cannot be built
``FormatError``        a file in one of the readers' formats that does not parse
``InfeasibleAssembly`` (a ``SpecError``) an assembly with no complete sequence
``StateLimit``         (a ``SpecError``) a state graph over ``max_states`` or its memory
``GameLimit``          (a ``GameError``) a game over its node limit
``Interpenetration``   (a ``GeometryError``, :mod:`cad.errors`) parts overlapping deeper
                       than their tolerance; ``pairs`` names them
=====================  ====================================================================

The limits and failures are typed so that a caller decides by type (build subassemblies,
stop a curve early, write the overlapping pairs commented), never by reading the message;
each keeps its parent, so the command line still answers with the same one line and exit
code 2.
"""

from __future__ import annotations

from cad.errors import AsmplanError, GeometryError, Interpenetration


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


class InfeasibleAssembly(SpecError):
    """An assembly with no complete sequence (the message names the root cause)."""


class StateLimit(SpecError):
    """A state graph that would exceed ``max_states`` or the memory it may use (the message
    says which, and what to change)."""


class GameLimit(GameError):
    """A game that would exceed its node limit (the message names the flag that bounds it)."""


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
