"""Hand-made specs and relation tables for the assembly tests (no meshes needed)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from asp.spec import spec_from_dict

D = {"+x": 0, "-x": 1, "+y": 2, "-y": 3, "+z": 4, "-z": 5}
OPPOSITE = {0: 1, 1: 0, 2: 3, 3: 2, 4: 5, 5: 4}


@dataclass(frozen=True)
class FakeRelations:
    """The cad Relations contract: ``parts``, ``tc``, ``tt`` of shape (n, n, 6)."""

    parts: tuple
    tc: np.ndarray
    tt: np.ndarray


def relations(parts, contacts=(), blocks=()):
    """Relations from ``contacts`` ``(i, j, d)`` (j on the d side of i; mirrored) and
    ``blocks`` ``(i, j, d)`` (i cannot move along d past j; mirrored: j cannot move along -d)."""
    n = len(parts)
    idx = {p: k for k, p in enumerate(parts)}
    tc = np.zeros((n, n, 6), dtype=bool)
    tt = np.ones((n, n, 6), dtype=bool)
    for i, j, d in contacts:
        tc[idx[i], idx[j], D[d]] = True
        tc[idx[j], idx[i], OPPOSITE[D[d]]] = True
    for i, j, d in blocks:
        tt[idx[i], idx[j], D[d]] = False
        tt[idx[j], idx[i], OPPOSITE[D[d]]] = False
    for k in range(n):
        tt[k, k] = True
    return FakeRelations(tuple(parts), tc, tt)


LATERAL = ("+x", "-x", "+y", "-y")


def stack_relations():
    """Base B, plate P resting on B, screw S through P into B (head on P)."""
    blocks = [("P", "B", "-z"), ("S", "B", "-z"), ("S", "P", "-z")]
    blocks += [("S", q, d) for q in ("P", "B") for d in LATERAL]
    return relations(
        ("B", "P", "S"),
        contacts=[("P", "B", "-z"), ("S", "P", "-z")],
        blocks=blocks,
    )


def stack_spec(**overrides):
    data = {
        "name": "stack",
        "parts": [
            {"id": "B", "file": "b.stl"},
            {"id": "P", "file": "p.stl"},
            {"id": "S", "file": "s.stl"},
        ],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "B",
        "gripper_approach": ["+z"],
        "operations": [
            {"id": "p", "agents": {"H": 3, "R": 2}, "part": "P"},
            {"id": "s", "agents": {"R": 4}, "part": "S"},
        ],
    }
    data.update(overrides)
    return spec_from_dict(data, source="stack.yaml")


def precedence_spec(n, pairs, tools=None, extra_ops=None):
    """n operations "0".."n-1", explicit precedence pairs (a before b), agent "any"."""
    after = {k: [] for k in range(n)}
    for a, b in pairs:
        after[b].append(str(a))
    ops = [{"id": str(k), "agents": {"any": 1 + k % 3}, "after": after[k]} for k in range(n)]
    ops += list(extra_ops or [])
    data = {"agents": {"any": {"side": "any"}}, "operations": ops}
    if tools:
        data["tools"] = tools
    return spec_from_dict(data, source="precedence.yaml")


def brute_force_sequences(n, pairs):
    """Number of permutations of range(n) that respect every (a before b) pair."""
    count = 0
    for perm in itertools.permutations(range(n)):
        pos = {v: k for k, v in enumerate(perm)}
        if all(pos[a] < pos[b] for a, b in pairs):
            count += 1
    return count


def brute_force_downsets(n, pairs):
    """Number of precedence-closed subsets of range(n)."""
    count = 0
    for mask in range(1 << n):
        if all(not (mask >> b & 1) or (mask >> a & 1) for a, b in pairs):
            count += 1
    return count


def pin_roller_ring(n: int = 3):
    """(spec, relations): a plate with ``n`` pins standing in it, a roller resting on each
    pin's shoulder and held all round by it, a cover resting on the pins over the rollers.
    Each pin with its roller is one block of a class of interchangeable blocks."""
    pins = [f"pin{k}" for k in range(n)]
    rollers = [f"roller{k}" for k in range(n)]
    parts = ("plate", *pins, *rollers, "cover")
    contacts = [(p, "plate", "-z") for p in pins]
    contacts += [(r, p, "-z") for p, r in zip(pins, rollers, strict=True)]
    contacts += [("cover", p, "-z") for p in pins]
    blocks = [(p, "plate", d) for p in pins for d in ("-z", *LATERAL)]
    blocks += [(r, p, d) for p, r in zip(pins, rollers, strict=True) for d in ("-z", *LATERAL)]
    blocks += [("cover", q, "-z") for q in (*pins, *rollers)]
    ops = [{"id": p, "agents": {"H": 2, "R": 3}, "part": p} for p in pins]
    ops += [{"id": r, "agents": {"H": 3, "R": 3}, "part": r} for r in rollers]
    ops += [{"id": "cover", "agents": {"H": 3, "R": 2}, "part": "cover"}]
    data = {
        "name": "ring",
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": "plate",
        "operations": ops,
    }
    return spec_from_dict(data, source="ring.yaml"), relations(parts, contacts, blocks)


CELL = {
    "name": "cell",
    "agents": {"H": {"side": "human"}, "R1": {"side": "robot"}, "R2": {"side": "robot"}},
    "tools": {"R1.bit": {"initial": "hex", "change_time": 3}},
    "cost": "time",
    "operations": [
        {"id": "a", "description": "prepare", "agents": {"H": 2, "R2": 4}},
        {"id": "b", "description": "place base", "agents": {"H": 5, "R1": 3}, "after": ["a"]},
        {"id": "c", "description": "fit cover", "agents": {"H": 4}, "after": ["a"]},
        {
            "id": "d",
            "description": "change bit",
            "agents": {"H": 6},
            "requires": {"R1.bit": "hex"},
            "sets": {"R1.bit": "cross"},
        },
        {
            "id": "e",
            "description": "screw",
            "agents": {"R1": 2, "H": 9},
            "requires": {"R1.bit": "cross"},
            "after": ["b", "c"],
        },
        {"id": "f", "description": "inspect", "agents": {"R2": 1, "H": 1}, "after": ["e"]},
    ],
}


def parts_spec(parts, source, durations=None):
    """A spec placing each part but the first (the base) alone, agents H and R
    (``durations(k, part)`` -> ``{"H": s, "R": s}``; default 2 s and 3 s)."""
    ops = [
        {"id": p, "agents": durations(k, p) if durations else {"H": 2, "R": 3}, "part": p}
        for k, p in enumerate(parts[1:])
    ]
    data = {
        "parts": [{"id": p, "file": f"{p}.stl"} for p in parts],
        "agents": {"H": {"side": "human"}, "R": {"side": "robot"}},
        "base_part": parts[0],
        "operations": ops,
    }
    return spec_from_dict(data, source=source)
