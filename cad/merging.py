"""Parts of one sub-assembly of the file that overlap each other: one rigid part.

Scene files of purchased parts and visualisation assets model a component in pieces that
overlap for real (Khronos' ``2CylinderEngine.glb``: each valve spring is ten coil links;
an XBee module's pins inside its chip). Those pieces are never assembled one by one.

Rule (:func:`merge_overlapping`): two parts that overlap deeper than their tolerance
(:func:`cad.freedom.overlaps`, the check the relations make) and lie in one group of the
file's hierarchy (:attr:`cad.assembly.Assembly.groups`) are one rigid part; parts joined
so, transitively, make one part. Its id is the innermost group's when the part is that
whole group, else its first member's; its mesh is the members' meshes together, its
source ``file#a+b+c`` (how a spec names such a part: :mod:`cad.loading`).
One warning names every part made so. Overlapping parts of no common group stay parts
(the relations then report them, with the spec line that joins them).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import trimesh

from cad.assembly import Assembly, Part


def merge_overlapping(assembly: Assembly, file_name: str) -> Assembly:
    """``assembly`` with the overlapping parts of each file group joined (module rule)."""
    if not assembly.groups or len(assembly.parts) < 2:
        return assembly
    from cad.freedom import overlaps
    from cad.tolerances import resolve_tolerances

    ids = [p.id for p in assembly.parts]
    grouped = _group_pairs(ids, assembly.groups)
    if not grouped:
        return assembly
    root = list(range(len(ids)))

    def find(k: int) -> int:
        while root[k] != k:
            root[k] = root[root[k]]
            k = root[k]
        return k

    for found in overlaps(assembly, resolve_tolerances(assembly)):
        if (found.a, found.b) in grouped:
            root[find(found.b)] = find(found.a)
    members: dict[int, list[int]] = {}
    for k in range(len(ids)):
        members.setdefault(find(k), []).append(k)
    joined = [m for m in members.values() if len(m) > 1]
    if not joined:
        return assembly
    return _joined(assembly, joined, file_name)


def _group_pairs(ids: list[str], groups) -> set[tuple[int, int]]:
    """Index pairs ``(a, b)``, ``a < b``, of parts that share a group of the file."""
    index = {pid: k for k, pid in enumerate(ids)}
    pairs = set()
    for _, group in groups:
        inside = sorted(index[m] for m in group if m in index)
        pairs |= {(a, b) for n, a in enumerate(inside) for b in inside[n + 1 :]}
    return pairs


def _joined(assembly: Assembly, joined: list[list[int]], file_name: str) -> Assembly:
    """The assembly with each list of part indices in ``joined`` made one part."""
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
        name = " + ".join(dict.fromkeys(parts[k].name for k in members))
        made[members[0]] = replace(
            parts[members[0]], id=pid, name=name, mesh=mesh, source=f"{file}#{'+'.join(ids)}"
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
    warnings.warn(
        f"{file_name}: parts of one sub-assembly of the file overlap each other, each set "
        f"taken as one rigid part (a component modelled in pieces; cad/merging.py): {shown}",
        stacklevel=3,
    )
    return replace(assembly, parts=kept, groups=tuple(groups))


def _joined_id(ids: list[str], groups, taken: set[str]) -> str:
    """The innermost group's id when ``ids`` are that whole group, else the first id."""
    wanted = set(ids)
    for gid, group in reversed(groups):  # innermost last in the file's order
        if set(group) == wanted and gid not in taken:
            return gid
    return ids[0]
