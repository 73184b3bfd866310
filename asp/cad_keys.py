"""Spec keys that correct what the geometry says about parts: ``flex:``, ``overlap_ok:``.

A real product is not only rigid bodies. A snap fit's housing flexes over the axle it
locks: as rigid meshes, the two block each other along every direction, and no sequence
can assemble them (:func:`cad.freedom.locking_pairs`). The spec says so in one line::

    flex: [lever_housing]      # flexes while it is inserted: its blocking by the parts
                               # it locks with is ignored then

Rule (:func:`with_flex`): for a ``flex`` part ``f`` and every part ``j`` that blocks it
along all six directions, ``f`` may move along every direction past ``j`` (``TT[f, j, :]``
true): ``f`` can be inserted once ``j`` is in, while ``j`` stays blocked by ``f`` (so ``j``
goes first). Every other relation is kept.

:mod:`asp.spec` reads the key (:func:`parse_flex`); :func:`asp.graph.feasibility.load_relations`
applies it to the relations.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

FLEX_KEY = "flex"
OVERLAP_KEY = "overlap_ok"


def parse_flex(value, part_ids, source: str) -> tuple[str, ...]:
    """The ``flex:`` list of a spec: part ids (a one-line ValueError for anything else).

    Parameters
    ----------
    value : object
        The YAML value (None: no key).
    part_ids : collection of str
        The spec's part ids (empty: not checked, a spec without a parts list).
    source : str
        The spec file, for messages.
    """
    if value is None:
        return ()
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str | int) for v in value):
        raise ValueError(f"{source}: flex: expected a list of part ids, got {value!r}")
    out = tuple(str(v) for v in value)
    unknown = [p for p in out if part_ids and p not in part_ids]
    if unknown:
        raise ValueError(f"{source}: flex: unknown part {unknown[0]!r}")
    return out


def with_flex(relations, flex: tuple[str, ...]):
    """``relations`` with each ``flex`` part free to pass the parts that block it along
    every direction (module docstring); unchanged when ``flex`` is empty."""
    if not flex or relations is None:
        return relations
    ids = [str(p) for p in relations.parts]
    tt = np.array(relations.tt, dtype=bool)
    for part in flex:
        if part not in ids:
            continue
        f = ids.index(part)
        walls = ~tt[f].any(axis=1)  # parts blocking f along every direction
        walls[f] = False
        tt[f, walls, :] = True
    return replace(relations, tt=tt)


def flex_hint(pairs: list[tuple[str, str]]) -> str:
    """The sentence an infeasible assembly starts with when parts lock each other."""
    if not pairs:
        return ""
    shown = "; ".join(f"{a} and {b}" for a, b in pairs[:4])
    more = f" and {len(pairs) - 4} more pair(s)" if len(pairs) > 4 else ""
    a, b = pairs[0]
    return (
        f"{shown}{more} block each other along every direction, so whichever goes in "
        f"second has no way in (if {b} flexes over {a}, a snap fit, the spec line "
        f"`flex: [{b}]` lets it in after {a}); "
    )


def parse_overlap_ok(value, part_ids, source: str) -> tuple[tuple[str, str], ...]:
    """The ``overlap_ok:`` list of a spec: pairs of part ids whose overlap in the file is as
    modelled (a press fit, a modelled thread, a visual asset's pieces), taken as touching
    (:func:`cad.fits.accepted_overlap`); a one-line ValueError for anything else.
    ``value`` is ``[[a, b], [c, d]]`` (one pair: ``[a, b]``); ``part_ids`` and ``source``
    as for :func:`parse_flex`.
    """
    if value is None:
        return ()
    if isinstance(value, list) and len(value) == 2 and all(isinstance(v, str) for v in value):
        value = [value]
    pairs = []
    for pair in value if isinstance(value, list) else [value]:
        if not (isinstance(pair, list) and len(pair) == 2):
            raise ValueError(
                f"{source}: {OVERLAP_KEY}: expected pairs of part ids ([[a, b], ...]), got {pair!r}"
            )
        a, b = (str(v) for v in pair)
        for part in (a, b):
            if part_ids and part not in part_ids:
                raise ValueError(f"{source}: {OVERLAP_KEY}: unknown part {part!r}")
        if a == b:
            raise ValueError(f"{source}: {OVERLAP_KEY}: a pair of one part {a!r}")
        pairs.append((a, b))
    return tuple(pairs)


__all__ = [
    "flex_hint",
    "parse_flex",
    "parse_overlap_ok",
    "with_flex",
]
"""What other modules may use (asmplan and arl among them)."""
