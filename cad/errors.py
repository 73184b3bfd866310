"""The project's exception family, rooted in the lowest package so every layer can raise it.

Every error the library raises for bad input is an :class:`AsmplanError`; it subclasses
``ValueError``, so code that catches ``ValueError`` keeps working. The command line turns
any of them into ``asmplan: error: <message>`` and exit code 2. Messages are one line and
name the file, part or operation at fault.

``cad`` defines the root and the geometry errors; :mod:`asp.errors` adds the planning ones
and :mod:`asmplan.errors` re-exports the whole family for users.
"""

from __future__ import annotations


class AsmplanError(ValueError):
    """Bad input or an impossible request, explained in one line."""


class GeometryError(AsmplanError):
    """Part geometry that cannot be used: unreadable mesh, deep interpenetration, bad units."""


class Interpenetration(GeometryError):
    """Parts that overlap deeper than their tolerance.

    ``pairs`` holds their part ids, the pairs a spec's ``overlap_ok:`` accepts, so that a
    caller (``asmplan init``) decides by type and reads the pairs, never the message.
    ``flex``: the parts a ``flex:`` line names for the pairs that lock each other once those
    are accepted; ``relations``: the relations computed with them accepted (None when not
    computed); ``unit_wrong``: the message blames the length unit instead.
    """

    def __init__(
        self, message: str, pairs=(), *, flex=(), relations=None, unit_wrong: bool = False
    ) -> None:
        super().__init__(message)
        self.pairs = tuple(tuple(pair) for pair in pairs)
        self.flex = tuple(flex)
        self.relations = relations
        self.unit_wrong = unit_wrong

    def __reduce__(self):
        return _interpenetration, (str(self), self.pairs, self.flex, self.unit_wrong)


def _interpenetration(message: str, pairs, flex, unit_wrong) -> Interpenetration:
    """An :class:`Interpenetration` rebuilt from its pickled fields (its relations left)."""
    return Interpenetration(message, pairs, flex=flex, unit_wrong=unit_wrong)
