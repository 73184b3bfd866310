"""Parts of one sub-assembly of the file that overlap or lock each other: one rigid part.

Scene files of purchased parts and visualisation assets model a component in pieces that
overlap for real (Khronos' ``2CylinderEngine.glb``: each valve spring is ten coil links;
an XBee module's pins inside its chip) or that lock each other (a patch cable's plug
moulded round its boot: each blocks the other along every direction). Those pieces are
never assembled one by one.

Which groups: only the file's *innermost* groups, those holding no other group of the
file (a component's own node: a spring, a valve's pieces), as the file is read. A group
holding groups is a sub-assembly of components (a cylinder head with its valves), and its
members overlapping each other is a press fit or a visual model's inaccuracy, for the
relations to report with the spec line that accepts it; never a reason to weld the
components into one. So a joined part never spans more than one innermost group, never
the whole product (the node over every part is no group, :mod:`cad.scene`).

Rule (:func:`merge_overlapping`), within each innermost group:

1. *Chains*: a group of three or more pieces, all one shape
   (:func:`cad.identical.alike_labels`), touching each other in one chain (the pieces'
   surfaces within the pair's contact tolerance, FCL distance: they connect all of them,
   and none touches more than two others, the one before and the one after it) is one
   part: a spring modelled as its coil links (Khronos' ``2CylinderEngine``: each valve
   spring is ten links, each touching the next end to end, none locking its neighbour), a
   chain's links, a bead string. Identical copies of a purchased part that are assembled
   one by one (screws, washers of one group) do not touch each other in a chain; two
   identical gears meshing are two pieces, never a chain; when they do (a stack of three
   identical spacers), the spec's parts name them one by one.
2. *Overlaps and locks*: two parts of the group that either overlap deeper than their
   tolerance (:func:`cad.freedom.overlaps`, the check the relations make) or, clear of each
   other, *lock* each other (each blocked by the other along all six directions,
   :func:`cad.freedom.translational_freedom` of the pair alone) are one rigid part; parts
   joined so, transitively, make one part, and the joined parts are checked again (a part
   joined of pieces may lock the next piece).

Why locking pieces are one part: blocking is a relation of the pair alone (a third part
never frees a direction), so of two parts locking each other whichever is placed second
has no way in, whatever the order and whatever else is there: as rigid bodies the file
cannot be assembled at all. A sub-assembly of the file that holds such a pair is therefore
a component that came assembled (or is assembled by flexing, which the file's geometry
cannot show). Planning it as one rigid part changes only files that had no plan (a file
without such a pair is as before), and removes no way the rest can be assembled.

Its id is the innermost group's when the part is that whole group and the file names
the group, else its first member's; its mesh is the members' meshes together, its source
``file#a+b+c`` (how a spec names such a part: :mod:`cad.loading`), every node of the file
it holds (a part joined of parts joined before lists their nodes, so a spec written from
it reads the same mesh).
One warning names every part made so. Overlapping parts of no common innermost group stay
parts (the relations then report them, with the spec lines that accept or join them).
"""

from __future__ import annotations

import re
import warnings
from dataclasses import replace

import numpy as np
import trimesh

from cad.assembly import Assembly, Part
from cad.faces import bounds_overlap
from cad.freedom import eroded_meshes, overlaps
from cad.tolerances import Tolerances, resolve_tolerances

UNNAMED_GROUP = re.compile(r"group(_\d+)?")
"""The id :mod:`cad.scene` gives a group node the file leaves unnamed."""


def merge_overlapping(assembly: Assembly, file_name: str) -> Assembly:
    """``assembly`` with the pieces of each innermost file group that make one component
    joined (module rule: chains, then overlaps and locks)."""
    if not assembly.groups or len(assembly.parts) < 2:
        return assembly
    inner = innermost_groups(assembly.groups)
    chains = chain_groups(assembly, inner)
    if chains:
        assembly = _joined(assembly, chains, file_name, "chain")
    if not _group_pairs([p.id for p in assembly.parts], assembly.groups, inner):
        return assembly
    tols = resolve_tolerances(assembly)
    eroded = eroded_meshes(assembly, tols.shrink)
    overlapping = {(o.a, o.b) for o in overlaps(assembly, tols, eroded)}
    grouped = _group_pairs([p.id for p in assembly.parts], assembly.groups, inner)
    why, joined = "overlap", _classes(len(assembly.parts), overlapping & grouped)
    for _ in range(len(assembly.parts)):  # each round joins parts: it ends
        if joined:
            assembly = _joined(assembly, joined, file_name, why)
            tols = resolve_tolerances(assembly)
            eroded = eroded_meshes(assembly, tols.shrink)
            overlapping = {(o.a, o.b) for o in overlaps(assembly, tols, eroded)}
        grouped = _group_pairs([p.id for p in assembly.parts], assembly.groups, inner)
        locked = _locked(assembly, tols, eroded, sorted(grouped - overlapping))
        if not locked:
            break
        why, joined = "lock", _classes(len(assembly.parts), locked)
    return assembly


def innermost_groups(groups) -> frozenset[str]:
    """Ids of the groups holding no other group (no group's members a proper subset of
    theirs): the file's components (module docstring)."""
    sets = [(gid, frozenset(members)) for gid, members in groups]
    return frozenset(gid for gid, mine in sets if not any(other < mine for _, other in sets))


def chain_groups(assembly: Assembly, inner: frozenset[str]) -> list[list[int]]:
    """Part indices of each innermost group of three or more pieces, all one shape,
    touching each other in one chain (module rule 1)."""
    import fcl
    from scipy.sparse.csgraph import connected_components

    from cad.contact import fcl_object
    from cad.identical import alike_labels

    index = {p.id: k for k, p in enumerate(assembly.parts)}
    chains = []
    tols = None
    for gid, group in assembly.groups:
        members = [index[m] for m in group if m in index]
        if gid not in inner or len(members) < 3:
            continue
        if len(set(alike_labels([assembly.parts[k].mesh for k in members]))) != 1:
            continue
        tols = tols or resolve_tolerances(assembly)
        objects = [fcl_object(assembly.parts[k].mesh) for k in members]
        touch = np.zeros((len(members), len(members)), bool)
        for i, a in enumerate(members):
            for j in range(i + 1, len(members)):
                b, gap = members[j], tols.contact_pair(a, members[j])
                if not bounds_overlap(assembly.parts[a].bounds, assembly.parts[b].bounds, pad=gap):
                    continue
                dist = fcl.distance(
                    objects[i], objects[j], fcl.DistanceRequest(), fcl.DistanceResult()
                )
                touch[i, j] = dist <= gap
        touch |= touch.T
        in_a_chain = touch.sum(axis=1).max() <= 2  # each touches the one before and after
        if in_a_chain and connected_components(touch, directed=False)[0] == 1:
            chains.append(members)
    return chains


def _locked(assembly: Assembly, tols, eroded, pairs) -> list[tuple[int, int]]:
    """Of ``pairs`` (part indices), those whose parts block each other along all six
    directions (module rule): the pair's translational freedom, computed for the two parts
    alone (their boxes must meet, else neither can block the other both ways)."""
    from cad.freedom import translational_freedom

    found = []
    for a, b in pairs:
        if not bounds_overlap(eroded[a].bounds, eroded[b].bounds):
            continue
        pair = Assembly(parts=(assembly.parts[a], assembly.parts[b]), units=assembly.units)
        reach = None if tols.reach is None else np.asarray(tols.reach)[[a, b]]
        pair_tols = Tolerances(tols.contact, np.asarray(tols.shrink)[[a, b]], tols.explicit, reach)
        tt = translational_freedom(
            pair, penetration_tol=pair_tols, check=False, eroded=[eroded[a], eroded[b]]
        )
        if not tt[0, 1].any() and not tt[1, 0].any():
            found.append((a, b))
    return found


def _classes(n: int, pairs) -> list[list[int]]:
    """The classes of two or more of ``n`` indices joined, transitively, by ``pairs``."""
    root = list(range(n))

    def find(k: int) -> int:
        while root[k] != k:
            root[k] = root[root[k]]
            k = root[k]
        return k

    for a, b in pairs:
        root[find(b)] = find(a)
    members: dict[int, list[int]] = {}
    for k in range(n):
        members.setdefault(find(k), []).append(k)
    return [m for m in members.values() if len(m) > 1]


def _group_pairs(ids: list[str], groups, inner: frozenset[str]) -> set[tuple[int, int]]:
    """Index pairs ``(a, b)``, ``a < b``, of parts that share an innermost group of the file
    (``inner``: the groups' ids)."""
    index = {pid: k for k, pid in enumerate(ids)}
    pairs = set()
    for gid, group in groups:
        if gid not in inner:
            continue
        inside = sorted(index[m] for m in group if m in index)
        pairs |= {(a, b) for n, a in enumerate(inside) for b in inside[n + 1 :]}
    return pairs


def _joined(assembly: Assembly, joined: list[list[int]], file_name: str, why: str) -> Assembly:
    """The assembly with each list of part indices in ``joined`` made one part (``why``:
    ``"chain"``, ``"overlap"`` or ``"lock"``, for the warning)."""
    parts = list(assembly.parts)
    new_id: dict[str, str] = {}
    made: dict[int, Part] = {}
    said = []
    taken = {p.id for p in parts}
    for members in joined:
        ids = [parts[k].id for k in members]
        pid = _joined_id(ids, assembly.groups, taken)
        taken.add(pid)
        mesh = trimesh.util.concatenate([parts[k].mesh for k in members])
        file = parts[members[0]].source.partition("#")[0]
        nodes = [parts[k].source.partition("#")[2] or parts[k].id for k in members]
        name = " + ".join(dict.fromkeys(parts[k].name for k in members))
        made[members[0]] = replace(
            parts[members[0]], id=pid, name=name, mesh=mesh, source=f"{file}#{'+'.join(nodes)}"
        )
        new_id.update({m: pid for m in ids})
        said.append(f"{pid} ({len(ids)} parts)")
    dropped = {k for members in joined for k in members[1:]}
    kept = tuple(made.get(k, p) for k, p in enumerate(parts) if k not in dropped)
    groups = []
    for gid, group in assembly.groups:
        renamed = tuple(dict.fromkeys(new_id.get(m, m) for m in group))
        if len(renamed) >= 2:
            groups.append((gid, renamed))
    shown = ", ".join(said[:10]) + (f" and {len(said) - 10} more" if len(said) > 10 else "")
    how = {
        "chain": "are one shape touching each other in a chain (a spring's coils, a chain)",
        "overlap": "overlap each other",
        "lock": "lock each other (each blocks the other along every direction)",
    }[why]
    warnings.warn(
        f"{file_name}: parts of one sub-assembly of the file {how}, each set taken as one "
        f"rigid part (a component modelled in pieces; cad/merging.py): {shown}",
        stacklevel=4,
    )
    return replace(assembly, parts=kept, groups=tuple(groups))


def _joined_id(ids: list[str], groups, taken: set[str]) -> str:
    """The innermost group's id when ``ids`` are that whole group and the file names it,
    else the first id (a node the file leaves unnamed is ``group_<n>``, :mod:`cad.scene`:
    the engine's valve springs are ``spring_link_0_parts_1_1`` and ``_11``, the names of
    their first links, not ``group_8`` and ``group_10``)."""
    wanted = set(ids)
    for gid, group in reversed(groups):  # innermost last in the file's order
        if set(group) == wanted and gid not in taken and not UNNAMED_GROUP.fullmatch(gid):
            return gid
    return ids[0]
